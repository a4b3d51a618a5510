//! Where the stages run: four processes (`split`, the default) or the
//! estimator and the classifier in one (`estimator+classifier`: one iceoryx2
//! hop fewer between a sample and its event; the same events).

use crate::stages::{Stage, STAGES};

/// The processes of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// acquisition, estimator, classifier, recorder: one process each.
    Split,
    /// The estimator and the classifier in one process (`leakwatch stage estimator+classifier`).
    EstimatorClassifier,
}

/// The processes of the fused placement, in the order they start.
const FUSED_PROCESSES: [Stage; 3] = [Stage::Recorder, Stage::EstimatorClassifier, Stage::Acquisition];

impl Placement {
    /// `split` (or nothing) or `estimator+classifier`; the error names the choices.
    pub fn parse(text: Option<&str>) -> Result<Placement, String> {
        match text {
            None | Some("split") => Ok(Placement::Split),
            Some(t) if Stage::parse(t) == Some(Stage::EstimatorClassifier) => {
                Ok(Placement::EstimatorClassifier)
            }
            Some(other) => Err(format!(
                "--placement {other}: expected `split` (a process per stage) or `{}` (the estimator and \
                 the classifier in one process)",
                Stage::EstimatorClassifier
            )),
        }
    }

    /// The name `--placement` takes for it.
    pub fn name(self) -> &'static str {
        match self {
            Placement::Split => "split",
            Placement::EstimatorClassifier => Stage::EstimatorClassifier.name(),
        }
    }

    /// The processes to start, in order.
    pub(super) fn processes(self) -> &'static [Stage] {
        match self {
            Placement::Split => &STAGES,
            Placement::EstimatorClassifier => &FUSED_PROCESSES,
        }
    }

    /// The process that runs `stage` (as its stats frames name it).
    pub(super) fn process_of(self, stage: Stage) -> Stage {
        match (self, stage) {
            (Placement::EstimatorClassifier, Stage::Estimator | Stage::Classifier) => {
                Stage::EstimatorClassifier
            }
            _ => stage,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fused_placement_runs_estimator_and_classifier_in_one_process() {
        let p = Placement::parse(Some("estimator+classifier")).unwrap();
        let names: Vec<&str> = p.processes().iter().map(|s| s.name()).collect();
        assert_eq!(names, ["recorder", "estimator+classifier", "acquisition"]);
        assert_eq!(p.process_of(Stage::Classifier), Stage::EstimatorClassifier);
        assert_eq!(p.process_of(Stage::Recorder), Stage::Recorder);
        assert_eq!(Placement::parse(None).unwrap().processes().len(), 4);
        assert_eq!(
            Placement::parse(Some("split"))
                .unwrap()
                .process_of(Stage::Estimator),
            Stage::Estimator
        );
        assert!(Placement::parse(Some("fused"))
            .unwrap_err()
            .contains("expected `split`"));
    }
}
