//! The step-time rows of `leakwatch bench ekf` without the CLI (a release build
//! of this example is quick to make): `cargo run --release -p bench --example
//! ekf_step -- [STEPS]`. One line per layout: median, p99 and mean ns per
//! predict + update (each including the clock's cost), then the chain's throughput.
use bench::speed::{
    chain_throughput, chain_throughput_with_thesis, recorded_samples, step_time, timer_overhead_ns,
};
use filter::Tuning;

fn main() {
    // `profile chain [REPS]`: the default chain (the leak filter and the
    // classifier) REPS times (default once) over 60 s, untimed (for
    // `valgrind --tool=callgrind` or `perf record`); `profile chain-thesis
    // [REPS]`: the same with the thesis' baseline; `profile plant [REPS]`: the
    // default chain on the plant model, as `bench ekf`'s plant row runs it.
    let profile = std::env::args().nth(1).as_deref() == Some("profile");
    let chain = std::env::args().nth(2);
    if profile && matches!(chain.as_deref(), Some("chain" | "chain-thesis" | "plant")) {
        let reps = std::env::args().nth(3).and_then(|a| a.parse().ok()).unwrap_or(1);
        let tp = match chain.as_deref() {
            Some("chain") => chain_throughput(&recorded_samples(60.0), reps),
            Some("plant") => {
                let plant = bench::speed::plant_model();
                let samples = bench::speed::recorded_samples_on(&plant, "lift", 60.0);
                bench::speed::plant_chain_throughput(&samples, reps)
            }
            _ => chain_throughput_with_thesis(&recorded_samples(60.0), reps),
        };
        println!("{}", tp.samples);
        return;
    }
    // `profile 7|12 SECONDS`: the layout's steps in a loop, untimed (for `perf record`).
    if std::env::args().nth(1).as_deref() == Some("profile") {
        let states: u32 = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(7);
        let reps: u32 = std::env::args().nth(3).and_then(|a| a.parse().ok()).unwrap_or(10);
        let samples = recorded_samples(60.0);
        let mut t = if states == 7 {
            Tuning::thesis()
        } else {
            Tuning::sensor_derived()
        };
        t.states = states;
        let mut acc = 0.0;
        for _ in 0..reps {
            let mut e =
                filter::Estimator::new(model::ActuatorParams::default(), t.clone()).expect("estimator");
            let mut out = filter::Estimate::default();
            for s in &samples {
                e.on_sample_into(std::hint::black_box(s), &mut out);
                acc += out.nis;
            }
        }
        println!("{acc}");
        return;
    }
    // `digest`: every field of every estimate of both layouts (and of the plant
    // chain's stage) as raw bits into one hash, and the values themselves to
    // `DIR/<layout>.bin` when a directory is given: a change meant to leave the
    // estimates bit for bit must leave the hash; others are compared value by value.
    if std::env::args().nth(1).as_deref() == Some("digest") {
        let dir = std::env::args().nth(2);
        let samples = recorded_samples(60.0);
        let plant = bench::speed::plant_model();
        let plant_samples = bench::speed::recorded_samples_on(&plant, "lift", 60.0);
        let mut leak10 = Tuning::sensor_derived();
        leak10.states = 10;
        let runs = [
            ("s7", Tuning::thesis(), model::ActuatorParams::default(), &samples),
            ("s10", leak10, model::ActuatorParams::default(), &samples),
            (
                "s12",
                Tuning::sensor_derived(),
                model::ActuatorParams::default(),
                &samples,
            ),
            ("plant12", Tuning::sensor_derived(), plant.clone(), &plant_samples),
        ];
        for (name, t, params, samples) in runs {
            let mut e = filter::Estimator::new(params, t).expect("estimator");
            let mut vals: Vec<f64> = Vec::new();
            let mut flags = 0u64;
            for s in samples.iter() {
                let o = e.on_sample(s);
                flags = flags.wrapping_mul(31).wrapping_add(o.flags as u64);
                vals.extend_from_slice(&o.state);
                vals.extend_from_slice(&o.sigma);
                vals.extend_from_slice(&[o.bulk_scale, o.bulk_scale_sigma, o.nis]);
                vals.extend_from_slice(&o.residual);
                vals.extend_from_slice(&o.innovation);
                vals.extend_from_slice(&o.innovation_sigma);
                vals.extend_from_slice(&o.mae_pa);
                vals.extend_from_slice(o.offset_response_lpm_per_mpa.as_flattened());
                vals.extend_from_slice(o.span_response_lpm.as_flattened());
                vals.extend_from_slice(&o.position_offset_response_lpm_per_mm);
            }
            let mut h = 0xcbf29ce484222325u64;
            for v in &vals {
                h = (h ^ v.to_bits()).wrapping_mul(0x100000001b3);
            }
            println!("{name}: {h:016x} flags {flags:016x}");
            if let Some(d) = &dir {
                let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
                std::fs::write(format!("{d}/{name}.bin"), bytes).expect("write");
            }
        }
        return;
    }
    let steps: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(300_000);
    let samples = recorded_samples(60.0);
    let overhead = timer_overhead_ns(100_000);
    let mut leak10 = Tuning::sensor_derived();
    leak10.states = 10;
    let rows = [
        ("7-state thesis", Tuning::thesis()),
        ("10-state leak", leak10),
        ("12-state leak (default)", Tuning::sensor_derived()),
    ];
    println!("clock {overhead:.0} ns");
    for (name, t) in rows {
        let r = step_time(name, &t, &samples, steps, overhead);
        println!(
            "{name:>24}: median {:>5.0} ns  p99 {:>5.0}  mean {:>5.0}",
            r.median_ns, r.p99_ns, r.mean_ns
        );
    }
    if std::env::var_os("EKF_STEP_NO_CHAIN").is_some() {
        return;
    }
    let tp = chain_throughput(&samples, 3);
    println!("{:>24}: {:.0} samples/s", "chain", tp.samples_per_s);
    let tp = chain_throughput_with_thesis(&samples, 3);
    println!(
        "{:>24}: {:.0} samples/s",
        "chain, thesis baseline", tp.samples_per_s
    );
}
