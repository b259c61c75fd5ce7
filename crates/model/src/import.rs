//! Specs from the files of other tools: [`e2eeval`] reads TU Dortmund's
//! E2EEvaluation framework. An importer builds specs as text and writes
//! nothing; the caller writes them.

pub mod e2eeval;
