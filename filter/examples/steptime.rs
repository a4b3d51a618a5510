//! Quick timing of the estimator step per layout.
use filter::{Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};
fn main() {
    let sc = Scenario::by_name("loaded-sine", 1, 60.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), sc, FaultSchedule::default(), 1).unwrap();
    let samples = sim.run(60.0);
    for (name, mut t) in [("thesis", Tuning::thesis()), ("sensor", Tuning::sensor_derived())] {
        for n in [6, 7, 10, 11] {
            t.states = n;
            let mut e = Estimator::new(ActuatorParams::default(), t.clone()).unwrap();
            let t0 = std::time::Instant::now();
            let mut acc = 0.0;
            for s in &samples {
                acc += e.on_sample(s).nis;
            }
            let dt = t0.elapsed().as_secs_f64() / samples.len() as f64;
            println!("{name} N={n}: {:.0} ns/sample ({acc:.1})", dt * 1e9);
        }
    }
}
