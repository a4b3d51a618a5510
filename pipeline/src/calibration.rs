//! `leakwatch calibrate`'s search with the rig identified first: the search
//! for missing effects ([`calibrate::run_with_progress`]) from the identified
//! model, and, while it adds an effect on the force side that the force
//! balance takes from the model (a spring in front of the rod), the mass, the
//! friction and the spring identified again together and the search run
//! again, until it adds none.

use std::path::Path;

use calibrate::{CalibrateOptions, Calibration, Effect};
use config::Config;
use model::Sample;

/// Times the mass and friction are identified again after the search at most.
const MAX_REFITS: usize = 3;

/// Whether the search's `found` effect changes what the force balance of
/// [`identify::identify_mechanics`] subtracts from the pressure force (the
/// model's load), so that the mass and the friction are to be fitted again.
pub fn refits_mechanics(found: &calibrate::FoundEffect) -> bool {
    Effect::by_name(&found.name)
        .iter()
        .any(|e| matches!(e, Effect::SpringLoad))
}

/// The search for missing effects on `measured` (read from `input`) from the
/// model of `cfg` (already identified), telling `progress` each step; while
/// the search adds an effect that [`refits_mechanics`], the rig is identified
/// again on `input` with it in the model and the search repeated from there
/// (at most [`MAX_REFITS`] times). The result holds every round's effects,
/// the first model's gap before and the last one's after.
pub fn search_with_refit(
    input: &Path,
    cfg: &Config,
    measured: &[Sample],
    opts: &CalibrateOptions,
    progress: &dyn Fn(&str),
) -> Result<Calibration, String> {
    let search = |model: &model::ActuatorParams| {
        calibrate::run_with_progress(measured, model, opts, progress).map_err(|e| e.to_string())
    };
    let mut cal = search(&cfg.model)?;
    // the effects the latest search added start here
    let mut latest = 0;
    for _ in 0..MAX_REFITS {
        let Some(added) = cal.effects[latest..].iter().find(|e| refits_mechanics(e)) else {
            break;
        };
        eprintln!(
            "the search added {}, which the force balance takes from the model: the mass and the friction are identified again with it",
            added.name
        );
        // The force balance fits a spring in front of the rod together with the
        // mass and the friction where the model has none: the search's spring
        // (its stiffness and contact trade against each other over a short
        // penetration) is kept only where that fit resolves none.
        let searched = cal.model_after.load;
        let mut without = cal.model_after.clone();
        without.load.stiffness_n_per_m = 0.0;
        let mut again = crate::commission::identify_rig(
            input,
            &Config {
                model: without,
                ..cfg.clone()
            },
        )?;
        if again.model.load.stiffness_n_per_m == 0.0 {
            again.model.load = searched;
        }
        let next = search(&again.model)?;
        latest = cal.effects.len();
        cal = cal.followed_by(next);
    }
    Ok(cal)
}
