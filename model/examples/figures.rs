//! Prints the open-loop sine reference figures (docs/model.md#reference-figures) for both
//! friction presets.
use model::*;
fn main() {
    for preset in [FrictionPreset::Thesis, FrictionPreset::Smooth] {
        let rig = ActuatorParams::default().with_friction_preset(preset);
        let sc = Scenario::by_name("open-loop-sine", 0, 10.0).unwrap();
        let mut sim = Simulator::new(
            rig,
            SensorParams::ideal(),
            SimSettings::default(),
            sc,
            FaultSchedule::default(),
            1,
        )
        .unwrap();
        let t0 = std::time::Instant::now();
        let (mut xmin, mut xmax, mut p1s, mut p2s, mut n, mut qmax, mut vmax, mut stuck) =
            (f64::MAX, f64::MIN, 0.0, 0.0, 0.0, 0.0f64, 0.0f64, 0);
        for k in 0..10_000 {
            let _s = sim.step();
            let tr = *sim.truth();
            if k >= 2000 {
                xmin = xmin.min(tr.state[3]);
                xmax = xmax.max(tr.state[3]);
                p1s += tr.state[1];
                p2s += tr.state[2];
                n += 1.0;
                qmax = qmax.max(tr.forces.valve.q1_m3_s.abs());
                vmax = vmax.max(tr.state[4].abs());
                if tr.state[4].abs() <= 1e-3 {
                    stuck += 1;
                }
            }
        }
        println!("{preset:?}: amp {:.2} mm, mean x {:.4} m, mean p1 {:.3} MPa p2 {:.3} MPa, peak Q {:.2} L/min, peak v {:.3} m/s, stuck {:.0}% ({:?})",
            (xmax - xmin) / 2.0 * 1e3, (xmax + xmin) / 2.0, p1s / n / 1e6, p2s / n / 1e6, units::m3_s_to_lpm(qmax), vmax, stuck as f64 / 80.0, t0.elapsed());
    }
}
