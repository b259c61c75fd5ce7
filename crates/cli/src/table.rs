//! Plain aligned text tables for people: the text printer's
//! (`rtpipe_printer::text`), under the name the commands' text uses.

pub use rtpipe_printer::text::TextTable as Table;
