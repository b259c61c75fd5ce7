//! Helpers shared by the model's integration tests.

use rtpipe_model::{Spec, SpecError};

/// The single diagnostic of a refused spec: (location, message, help).
/// `what` names the input in the failure when it was accepted.
pub fn single_error(r: Result<Spec, SpecError>, what: &str) -> (String, String, String) {
    let e = match r {
        Ok(_) => panic!("accepted: {what}"),
        Err(e) => e,
    };
    assert_eq!(e.diagnostics.len(), 1, "{e}");
    let d = &e.diagnostics[0];
    (
        e.locations()[0].clone(),
        d.message.clone(),
        d.help.clone().unwrap_or_default(),
    )
}
