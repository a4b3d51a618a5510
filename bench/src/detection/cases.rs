//! The runs of the suite: each case drawn from the suite's seed, its rig
//! drawn from its own seed, and the simulator of its rig, fault and scenario.

use model::rng::Rng;
use model::{ActuatorParams, Fault, FaultSchedule, LeakPath, Scenario, Simulator};

use super::{Case, AFTER_ONSET_S, FROM_START, GAPS, HEALTHY_RUN_S, MID_RUN, SCENARIOS, SIZES_LPM};

/// Draws the rig of a run: the model with friction ±20 % and asymmetric,
/// bulk modulus −30..0 %, spool null bias up to ±10 % of the spool amplitude.
pub fn draw_rig(rng: &mut Rng) -> ActuatorParams {
    let mut rig = ActuatorParams::default();
    let mut ext = rig.friction.extend();
    let mut ret = ext;
    let fe = rng.uniform_in(0.8, 1.2);
    let fr = rng.uniform_in(0.8, 1.2);
    ext.static_n *= fe;
    ext.slip_n *= fe;
    ext.viscous_n_s_per_m *= fe;
    ret.static_n *= fr;
    ret.slip_n *= fr;
    ret.viscous_n_s_per_m *= fr;
    rig.friction.set_extend(ext);
    rig.friction.retract = Some(ret);
    rig.bulk_modulus_pa *= rng.uniform_in(0.7, 1.0);
    let spool_amplitude_m = rig.spool_gain_m_per_v * 3.0;
    rig.spool_null_bias_m = rng.uniform_in(-0.1, 0.1) * spool_amplitude_m;
    rig
}

/// The cases of a suite: `runs` per kind and size, and enough healthy runs for `hours`.
pub fn cases(runs: usize, hours: f64, seed: u64) -> Vec<Case> {
    let mut out = Vec::new();
    let mut rng = Rng::new(seed);
    for kind in ["ext1", "ext2", "int"] {
        for size in SIZES_LPM {
            for _ in 0..runs {
                let scenario = SCENARIOS[(rng.uniform() * SCENARIOS.len() as f64) as usize % SCENARIOS.len()];
                let onset = rng.uniform_in(15.0, 25.0);
                let ramp = if rng.uniform() < 0.5 {
                    0.0
                } else {
                    rng.uniform_in(0.5, 5.0)
                };
                out.push(Case {
                    seed: rng.next_u64(),
                    scenario: scenario.into(),
                    kind: kind.into(),
                    size_lpm: size,
                    onset_s: onset,
                    ramp_s: ramp,
                    seconds: onset + ramp + AFTER_ONSET_S,
                    variant: MID_RUN.into(),
                });
            }
            // The same leak present from t = 0, seen against a commissioning.
            for _ in 0..runs.div_ceil(2) {
                let scenario = SCENARIOS[(rng.uniform() * SCENARIOS.len() as f64) as usize % SCENARIOS.len()];
                out.push(Case {
                    seed: rng.next_u64(),
                    scenario: scenario.into(),
                    kind: kind.into(),
                    size_lpm: size,
                    onset_s: 0.0,
                    ramp_s: 0.0,
                    seconds: AFTER_ONSET_S,
                    variant: FROM_START.into(),
                });
            }
        }
    }
    let healthy = (hours * 3600.0 / HEALTHY_RUN_S).ceil() as usize;
    for i in 0..healthy {
        out.push(Case {
            seed: rng.next_u64(),
            scenario: SCENARIOS[i % SCENARIOS.len()].into(),
            kind: "none".into(),
            size_lpm: 0.0,
            onset_s: f64::NAN,
            ramp_s: 0.0,
            seconds: HEALTHY_RUN_S,
            // Every fourth healthy run loses samples in gaps.
            variant: if i % 4 == 3 { GAPS.into() } else { MID_RUN.into() },
        });
    }
    out
}

/// The simulated rig of a case: the rig drawn from its seed ([`draw_rig`]), its
/// fault (if any) and its scenario over `case.seconds`.
pub fn simulator_for(case: &Case) -> Result<Simulator, String> {
    let mut rng = Rng::new(case.seed);
    let rig = draw_rig(&mut rng);
    let mut faults = FaultSchedule::default();
    if let Some(path) = LeakPath::from_name(&case.kind) {
        let spec = format!(
            "{}:{}lpm@{}s,ramp={}",
            path.name(),
            case.size_lpm,
            case.onset_s,
            case.ramp_s
        );
        faults
            .faults
            .push(Fault::parse(&spec, &rig).map_err(|e| e.to_string())?);
    }
    let scenario = Scenario::by_name(&case.scenario, case.seed, case.seconds).map_err(|e| e.to_string())?;
    Simulator::with_default_sensors(rig, scenario, faults, case.seed).map_err(|e| e.to_string())
}

/// What happens to one sample of a `gaps` case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GapStep {
    /// The sample arrives.
    Kept,
    /// A gap of this many samples starts here: this sample is lost.
    Starts(u64),
    /// The sample is lost inside a gap.
    Lost,
}

/// The gaps of a `gaps` case, drawn from its seed: a run of 1-2000 lost samples
/// every 10-30 s of rig time.
#[derive(Debug, Clone)]
pub struct GapSchedule {
    rng: Rng,
    next_s: f64,
    left: u64,
}

impl GapSchedule {
    /// The schedule of the case whose seed is `seed`.
    pub fn new(seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0x9e37_79b9_7f4a_7c15);
        let next_s = rng.uniform_in(10.0, 30.0);
        GapSchedule { rng, next_s, left: 0 }
    }

    /// Whether the sample at `t_s` (s, 1 kHz, in order) arrives.
    pub fn step(&mut self, t_s: f64) -> GapStep {
        let mut started = None;
        if t_s >= self.next_s {
            let n = 1 + (self.rng.uniform() * 2000.0) as u64;
            self.left = n;
            self.next_s = t_s + n as f64 * 1e-3 + self.rng.uniform_in(10.0, 30.0);
            started = Some(n);
        }
        if self.left == 0 {
            return GapStep::Kept;
        }
        self.left -= 1;
        started.map_or(GapStep::Lost, GapStep::Starts)
    }
}
