//! A task's `body`: one of the flight controller's bodies
//! ([`crate::BODY_NAMES`]), refused at its key otherwise, so a misspelling
//! is caught by every command that reads the spec, not only by `fly`.

use super::{span, Builder};
use crate::input::shown_name;
use crate::raw::S;
use crate::BODY_NAMES;

impl Builder {
    /// The body of a task named `task`: `None` when it is not a known
    /// body (an error at its key), `Some(None)` when none is given.
    pub(super) fn body(&mut self, task: &str, b: Option<&S<String>>) -> Option<Option<String>> {
        let Some(b) = b else {
            return Some(None);
        };
        let name = b.get_ref();
        if BODY_NAMES.contains(&name.as_str()) {
            return Some(Some(name.clone()));
        }
        // The name is the user's: shown escaped, as every name in a message
        // (a terminal would obey an escape sequence in it).
        self.err(
            format!(
                "task `{}` names an unknown body \"{}\"",
                shown_name(task),
                shown_name(name)
            ),
            span(b),
            format!("use one of: {}", BODY_NAMES.join(", ")),
        );
        None
    }
}
