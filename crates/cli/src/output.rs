//! The files rtpipe writes: one writer for every crate, `rtpipe_model::output`
//! (atomic, exclusive temporaries, never over an input), re-exported here
//! so the commands name it `crate::output`.

pub use rtpipe_model::output::*;
