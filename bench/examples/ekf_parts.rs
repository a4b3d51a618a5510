//! Throughput of the parts of one filter step (model step, time update,
//! selector update), each repeated on one realistic snapshot of a filter
//! (after 5 s of the loaded sine): `ekf_parts [REPS]`. A tool to compare
//! variants of one part; `ekf_step` times the whole step as `bench ekf` does.
use std::hint::black_box;
use std::time::Instant;

use bench::speed::recorded_samples;
use filter::{Ekf, Tuning};
use model::process::ProcessModel;
use model::ActuatorParams;
use nalgebra::SVector;

const SCALE: [f64; 12] = [1e-5, 1e6, 1e6, 1e-3, 1e-2, 1e-2, 1e2, 1e-6, 1e-6, 1e-6, 1e-6, 1.0];

fn parts<const N: usize, const W: usize>(name: &str, tuning: &Tuning, reps: u32) {
    let samples = recorded_samples(6.0);
    let mut params = ActuatorParams::default();
    if N < 10 {
        params.supply_sag_pa_per_m3_s = 0.0;
    }
    let model = ProcessModel::new(params, tuning.sample_period_s);
    let mut x0 = SVector::<f64, N>::zeros();
    let s0 = &samples[0];
    x0[1] = s0.p1_pa;
    x0[2] = s0.p2_pa;
    x0[3] = s0.x_m;
    if N == 12 {
        x0[11] = 1.0;
    }
    let scale = SVector::<f64, N>::from_fn(|i, _| SCALE[i]);
    let mut e = Ekf::<N, 3, W>::new(
        x0,
        &tuning.p0_diag::<N>(),
        &tuning.q_diag::<N>(),
        tuning.r_diag(),
        scale,
    );
    let mut u = s0.u_v;
    for s in &samples[..5000] {
        let (x, f, _) = model.step(e.state(), u);
        e.predict(x, &f).expect("predict");
        let y = SVector::<f64, 3>::new(s.x_m, s.p1_pa, s.p2_pa);
        let _ = e.update_selected(&y, &ProcessModel::measure(e.state()), [3, 1, 2], [true; 3]);
        u = s.u_v;
    }
    let s = &samples[5000];
    let y = SVector::<f64, 3>::new(s.x_m, s.p1_pa, s.p2_pa);
    let (x_pred, f, _) = model.step(e.state(), u);
    println!(
        "x = {} m (stroke {}..{}), nnz(F) = {}",
        e.state()[3],
        model.params.x_min_m,
        model.params.x_max_m,
        f.iter().filter(|v| **v != 0.0).count()
    );
    let mut after_predict = e.clone();
    after_predict.predict(x_pred, &f).expect("predict");
    let time = |what: &str, run: &mut dyn FnMut() -> f64| {
        let mut best = f64::INFINITY;
        let mut sink = 0.0;
        for _ in 0..5 {
            let t0 = Instant::now();
            for _ in 0..reps {
                sink += run();
            }
            best = best.min(t0.elapsed().as_secs_f64() / reps as f64 * 1e9);
        }
        black_box(sink);
        println!("{name:>10} {what:>16}: {best:6.1} ns");
    };
    time("model step", &mut || {
        let (x, f, _) = model.step(black_box(e.state()), black_box(u));
        x[1] + f[(1, 1)]
    });
    time("predict", &mut || {
        let mut w = black_box(&e).clone();
        let _ = w.predict(black_box(x_pred), black_box(&f));
        w.state()[0]
    });
    time("update", &mut || {
        let mut w = black_box(&after_predict).clone();
        let i = w.update_selected(
            black_box(&y),
            &ProcessModel::measure(w.state()),
            [3, 1, 2],
            [true; 3],
        );
        i.map(|i| i.nis).unwrap_or(0.0)
    });
    time("sigma", &mut || black_box(&e).sigma()[0]);
    time("clone", &mut || black_box(&e).clone().state()[0]);
}

fn main() {
    let reps: u32 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200_000);
    parts::<7, 8>("7 states", &Tuning::thesis(), reps);
    parts::<12, 12>("12 states", &Tuning::sensor_derived(), reps);
}
