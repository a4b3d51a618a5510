//! The transducers' lag in a step: the NIS counts it, the gains do not.

use model::process::ProcessModel;
use model::ActuatorParams;
use nalgebra::SVector;

use super::{make_filter, step_filter, StepInput, StepMemory};
use crate::{outlier, BiasResponse, Estimate, Tuning};

/// One step of a 12-state filter from `measured` under command `u` (V),
/// reading `y`, with the lags `lag_s` counted: the
/// estimate.
fn step_once(
    model: &ProcessModel,
    measured: [f64; 3],
    u: f64,
    y: SVector<f64, 3>,
    lag_s: [f64; 2],
) -> Estimate {
    let tuning = Tuning::sensor_derived();
    let mut e = make_filter::<12, 12>(&tuning, model, Some(measured));
    let mut out = Estimate::empty(0.0, 12);
    let input = StepInput {
        pressure_lag_s: lag_s,
        ..StepInput::plain(u, y)
    };
    let memory = StepMemory {
        still_samples: &mut 0,
        offset_response: &mut BiasResponse::default(),
        outliers: &mut outlier::OutlierGate::default(),
    };
    step_filter(&mut e, model, &input, &mut out, memory).expect("a step");
    out
}

/// A full command from rest: the pressures move at MPa per ms. Readings
/// lagging by 0.5 ms behind the prediction: the NIS is the selector form's
/// with (τ·ṗ)² on each pressure's variance, ṗ the predicted rate, and below
/// the NIS without the lag; the estimate is the same bits.
#[test]
fn the_lag_widens_the_nis_not_the_gains() {
    let model = ProcessModel::new(ActuatorParams::vertical_lift(), 1e-3);
    let measured = [0.1, 8e6, 6e6];
    let u = 10.0;
    let tuning = Tuning::sensor_derived();
    let start = make_filter::<12, 12>(&tuning, &model, Some(measured));
    let (x_pred, _, _) = model.step(start.state(), u);
    let rates = ProcessModel::MEASURED_STATES.map(|i| (x_pred[i] - start.state()[i]) / model.dt_s);
    assert!(rates[1].abs() > 1e8, "ṗ1 {} Pa/s", rates[1]);
    let lag_s = [0.5e-3, 0.5e-3];
    let mut y = model.read(&x_pred);
    y[1] -= lag_s[0] * rates[1];
    y[2] -= lag_s[1] * rates[2];
    let plain = step_once(&model, measured, u, y, [0.0; 2]);
    let lagged = step_once(&model, measured, u, y, lag_s);
    assert_eq!(plain.state.map(f64::to_bits), lagged.state.map(f64::to_bits));
    // the selector form, from the prior the step predicted
    let mut prior = make_filter::<12, 12>(&tuning, &model, Some(measured));
    let (x_pred, f, _) = model.step(prior.state(), u);
    prior.predict(x_pred, &f).expect("predicted");
    let lag_var = [0.0, (lag_s[0] * rates[1]).powi(2), (lag_s[1] * rates[2]).powi(2)];
    let nu = y - model.read(prior.state());
    let want = prior
        .selected_nis(&nu, ProcessModel::MEASURED_STATES, lag_var, [true; 3])
        .expect("a NIS");
    assert!(
        (lagged.nis / want - 1.0).abs() < 1e-12,
        "{} against {want}",
        lagged.nis
    );
    assert!(lagged.nis < plain.nis, "{} against {}", lagged.nis, plain.nis);
}
