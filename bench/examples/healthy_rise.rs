//! How large do the leak-size detector's scores get on healthy runs? Runs the
//! healthy cases of the detection suite and prints, per run, the largest rise of
//! each hypothesis (ext1, ext2, int) above its learned offset once armed, raw and
//! smoothed, plus the largest score (rise - misfit)/floor.
//! cargo run --release -p bench --example healthy_rise -- [HOURS] [TAU_S]
use bench::detection::{cases, simulator_for, Case};
use detect::{misfits, Classifier, ClassifierConfig};
use filter::{EstimatorStage, Tuning};
use model::ActuatorParams;

fn run(case: &Case, tau_s: f64) -> ([f64; 3], [f64; 3]) {
    let mut sim = simulator_for(case).expect("sim");
    let mut stage = EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .expect("stage");
    let mut cls = Classifier::new(ClassifierConfig::default()).expect("cls");
    let mut max_raw = [f64::NEG_INFINITY; 3];
    let mut max_smooth = [f64::NEG_INFINITY; 3];
    let mut sm = [0.0f64; 3];
    let a = 1e-3 / tau_s;
    for _ in 0..(case.seconds * 1000.0) as usize {
        let s = sim.step();
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |_| {});
        if cls.leak_size.is_armed() {
            let r = cls.leak_size.rise_lpm(&e.leak);
            let misfit = misfits(r);
            for k in 0..3 {
                let v = r[k] - misfit[k];
                sm[k] += a * (v - sm[k]);
                max_raw[k] = max_raw[k].max(v);
                max_smooth[k] = max_smooth[k].max(sm[k]);
            }
        }
    }
    (max_raw, max_smooth)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let hours: f64 = a.get(1).map(|s| s.parse().expect("hours")).unwrap_or(10.0);
    let tau: f64 = a.get(2).map(|s| s.parse().expect("tau")).unwrap_or(0.5);
    let healthy: Vec<Case> = cases(12, hours, 2026)
        .into_iter()
        .filter(|c| c.kind == "none")
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let out = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= healthy.len() {
                    break;
                }
                let r = run(&healthy[i], tau);
                out.lock().expect("lock").push((i, r));
            });
        }
    });
    let mut v = out.into_inner().expect("lock");
    v.sort_by_key(|x| x.0);
    for (i, (raw, sm)) in &v {
        println!(
            "{:20} {:20} raw {:6.3} {:6.3} {:6.3} smooth {:6.3} {:6.3} {:6.3}",
            healthy[*i].scenario, healthy[*i].seed, raw[0], raw[1], raw[2], sm[0], sm[1], sm[2]
        );
    }
}
