//! Specs from the files of other tools: [`e2eeval`] reads TU Dortmund's
//! E2EEvaluation framework, [`px4_ulog`] PX4's flight logs. An importer builds specs as text and writes
//! nothing; the caller writes them.

pub mod e2eeval;
pub mod px4_ulog;
