//! Simpson's four-slot register (H. R. Simpson, "Four-slot fully asynchronous
//! communication mechanism", IEE Proceedings E 137(1), 1990): a wait-free
//! latest-value buffer between one writer and one reader. Neither side ever
//! waits for the other, retries or allocates; the reader always gets a
//! complete value (never a mix of two writes), the newest one whose write
//! had completed when the read began, or a newer one.
//!
//! Four data slots, arranged as two pairs of two, and four one-bit control
//! variables: `slot[p]` (the slot of pair p written last), `latest` (the pair
//! written last) and `reading` (the pair the reader announced).
//!
//! ```text
//! writer:  pair = !reading; index = !slot[pair];
//!          data[pair][index] = v; slot[pair] = index; latest = pair
//! reader:  pair = latest; reading = pair; index = slot[pair];
//!          v = data[pair][index]
//! ```
//!
//! Every control-variable access is `SeqCst`: the protocol needs the
//! store→load order "reader stores `reading`, then loads `slot[pair]`" (and
//! the writer's mirror image), which release/acquire does not give (a store
//! may be delayed past a later load in a store buffer, as on x86). The
//! correctness argument is in docs/runtime.md; `tests::model_check`
//! enumerates every interleaving of the protocol.

use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicU8, Ordering::SeqCst};
use std::sync::Arc;

/// One data slot on its own cache line.
#[repr(align(64))]
struct Slot<T>(UnsafeCell<T>);

/// A control variable on its own cache line (no false sharing between the
/// writer's and the reader's variables).
#[repr(align(64))]
struct Ctl(AtomicU8);

struct Shared<T> {
    data: [[Slot<T>; 2]; 2],
    slot: [Ctl; 2],
    latest: Ctl,
    reading: Ctl,
}

// SAFETY: the data slots are only accessed through the one `Writer` and the
// one `Reader` (neither is `Clone`, both need `&mut self`), and the protocol
// guarantees they never access the same slot at the same time (see
// `Writer::write` and docs/runtime.md); `T: Send` because values move
// between threads by copy.
unsafe impl<T: Send> Sync for Shared<T> {}

/// Creates a register holding `initial`: its writer and its reader.
pub fn register<T: Copy + Send>(initial: T) -> (Writer<T>, Reader<T>) {
    let slot = || Slot(UnsafeCell::new(initial));
    let shared = Arc::new(Shared {
        data: [[slot(), slot()], [slot(), slot()]],
        slot: [Ctl(AtomicU8::new(0)), Ctl(AtomicU8::new(0))],
        latest: Ctl(AtomicU8::new(0)),
        reading: Ctl(AtomicU8::new(0)),
    });
    (
        Writer {
            shared: Arc::clone(&shared),
        },
        Reader {
            shared,
            announced: 0,
        },
    )
}

/// The single writer of a register. `Send`, not `Clone`.
pub struct Writer<T> {
    shared: Arc<Shared<T>>,
}

/// The single reader of a register. `Send`, not `Clone`.
pub struct Reader<T> {
    shared: Arc<Shared<T>>,
    /// What this reader last stored in `reading` (it is the only one that
    /// stores it).
    announced: u8,
}

impl<T: Copy> Writer<T> {
    /// Publishes `v`: wait-free, a bounded number of steps.
    pub fn write(&mut self, v: T) {
        let s = &*self.shared;
        let pair = (1 ^ s.reading.0.load(SeqCst)) as usize;
        let index = (1 ^ s.slot[pair].0.load(SeqCst)) as usize;
        // SAFETY: the reader never accesses data[pair][index] while we write
        // it. Either the reader's current or next read uses the other pair
        // (`pair` = !reading as we loaded it), or it announced `pair` after
        // our load of `reading`; then (SeqCst: its store of `reading`
        // precedes its load of `slot[pair]` in the single total order) it
        // loads `slot[pair]` after our load of it and before or after our
        // store below: before, it sees the old value, which is !index; after,
        // we have finished writing. The exhaustive model check in
        // `tests::model_check` covers every interleaving. `&mut self`: one
        // writer.
        unsafe { s.data[pair][index].0.get().write(v) };
        s.slot[pair].0.store(index as u8, SeqCst);
        s.latest.0.store(pair as u8, SeqCst);
    }
}

impl<T: Copy> Reader<T> {
    /// The newest complete value: wait-free, a bounded number of steps.
    pub fn read(&mut self) -> T {
        let s = &*self.shared;
        let pair = s.latest.0.load(SeqCst) as usize;
        // Only the reader stores `reading`: when it already names `pair`,
        // the store would not change it (nor what any interleaving of the
        // writer sees), so the fence it costs is skipped. Under a writer
        // that keeps writing, `latest` moves away on every write and the
        // store is made each time.
        if pair as u8 != self.announced {
            s.reading.0.store(pair as u8, SeqCst);
            self.announced = pair as u8;
        }
        let index = s.slot[pair].0.load(SeqCst) as usize;
        // SAFETY: the writer does not write data[pair][index] while we read
        // it: it writes pair `pair` only when it loaded `reading` before our
        // store above, and then into the slot other than the one `slot[pair]`
        // named when it loaded it; a write it starts after seeing our
        // announcement goes to the other pair (argument in docs/runtime.md,
        // checked by `tests::model_check`). `&mut self`: one reader.
        unsafe { s.data[pair][index].0.get().read() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_what_was_written_last() {
        let (mut w, mut r) = register([0u64; 8]);
        assert_eq!(r.read(), [0; 8]);
        for k in 1..100u64 {
            w.write([k; 8]);
            assert_eq!(r.read(), [k; 8]);
            assert_eq!(r.read(), [k; 8]);
        }
        w.write([7; 8]);
        w.write([8; 8]);
        assert_eq!(r.read(), [8; 8]);
    }

    #[test]
    fn carries_stamped_values_across_threads() {
        use rtpipe_body::{Stamp, Stamped};
        let (mut w, mut r) = register::<Option<Stamped<f64>>>(None);
        let h = std::thread::spawn(move || {
            for job in 0..1000u64 {
                let stamp = Stamp {
                    task: 3,
                    job,
                    read: job as i64,
                    publish: job as i64 + 1,
                };
                w.write(Some(Stamped {
                    value: job as f64,
                    stamp,
                }));
            }
        });
        let mut last = None;
        while last.is_none_or(|j| j < 999) {
            if let Some(v) = r.read() {
                assert_eq!(v.value, v.stamp.job as f64);
                assert_eq!(v.stamp.publish, v.stamp.read + 1);
                assert!(last.is_none_or(|j| j <= v.stamp.job));
                last = Some(v.stamp.job);
            }
        }
        assert!(h.join().is_ok());
    }

    /// An explicit-state model checker of the control protocol under
    /// sequential consistency: every interleaving of a writer doing
    /// `WRITES` writes and a reader doing `READS` reads, each step one
    /// control-variable access or the start or end of a data access.
    mod model_check {
        use std::collections::HashSet;

        /// Which protocol to check: the real one, or broken variants that
        /// the checker must reject (so it is not vacuous).
        #[derive(Clone, Copy, PartialEq)]
        enum Variant {
            Simpson,
            /// The reader skips the announcement when `reading` already
            /// names the pair (what `Reader::read` does).
            SkipSameAnnounce,
            /// The reader does not announce its pair.
            NoAnnounce,
            /// The writer reuses the slot it wrote last.
            SameIndex,
            /// The reader loads `slot` before announcing its pair (what a
            /// store→load reordering does to the real protocol).
            LoadBeforeAnnounce,
        }

        #[derive(Clone, PartialEq, Eq, Hash)]
        struct State {
            latest: u8,
            reading: u8,
            slot: [u8; 2],
            /// The sequence number held by each data slot.
            data: [[u8; 2]; 2],
            wpc: u8,
            wpair: u8,
            windex: u8,
            writes: u8,
            rpc: u8,
            rpair: u8,
            rindex: u8,
            reads: u8,
            /// The newest write completed (its `latest` store done) when
            /// the current read began, and the last value read.
            floor: u8,
            last_read: u8,
        }

        const WRITES: u8 = 4;
        const READS: u8 = 4;

        /// The writer's steps: 0 load reading, 1 load slot, 2 start the
        /// data write, 3 end it, 4 store slot, 5 store latest.
        fn writer_step(s: &State, v: Variant) -> Option<State> {
            if s.writes == WRITES {
                return None;
            }
            let mut n = s.clone();
            match s.wpc {
                0 => n.wpair = 1 ^ s.reading,
                1 => {
                    n.windex = if v == Variant::SameIndex {
                        s.slot[s.wpair as usize]
                    } else {
                        1 ^ s.slot[s.wpair as usize]
                    }
                }
                2 => {}
                3 => n.data[s.wpair as usize][s.windex as usize] = s.writes + 1,
                4 => n.slot[s.wpair as usize] = s.windex,
                _ => {
                    n.latest = s.wpair;
                    n.writes += 1;
                }
            }
            n.wpc = (s.wpc + 1) % 6;
            Some(n)
        }

        /// The reader's steps: 0 load latest, 1 store reading, 2 load slot,
        /// 3 start the data read, 4 end it (the value is checked then).
        fn reader_step(s: &State, v: Variant) -> Option<State> {
            if s.reads == READS {
                return None;
            }
            let mut n = s.clone();
            let (announce, load) = match v {
                Variant::LoadBeforeAnnounce => (2, 1),
                _ => (1, 2),
            };
            match s.rpc {
                0 => {
                    n.rpair = s.latest;
                    n.floor = s.writes;
                }
                pc if pc == announce => {
                    let skip = match v {
                        Variant::NoAnnounce => true,
                        Variant::SkipSameAnnounce => s.reading == s.rpair,
                        _ => false,
                    };
                    if !skip {
                        n.reading = s.rpair;
                    }
                }
                pc if pc == load => n.rindex = s.slot[s.rpair as usize],
                3 => {}
                _ => {
                    n.last_read = s.data[s.rpair as usize][s.rindex as usize];
                    n.reads += 1;
                }
            }
            n.rpc = (s.rpc + 1) % 5;
            Some(n)
        }

        /// The first violated property in `s`, if any.
        fn violation(s: &State, before: &State) -> Option<&'static str> {
            let writing = s.wpc == 3;
            let reading = s.rpc == 4;
            if writing && reading && s.wpair == s.rpair && s.windex == s.rindex {
                return Some("the reader and the writer access the same slot");
            }
            if s.reads > before.reads {
                if s.last_read < before.last_read {
                    return Some("a read returned an older value than the previous read");
                }
                if s.last_read < s.floor {
                    return Some("a read missed a write completed before it began");
                }
            }
            None
        }

        /// Explores every reachable state; the states visited, or the first
        /// violation.
        fn check(v: Variant) -> Result<usize, &'static str> {
            let init = State {
                latest: 0,
                reading: 0,
                slot: [0, 0],
                data: [[0; 2]; 2],
                wpc: 0,
                wpair: 0,
                windex: 0,
                writes: 0,
                rpc: 0,
                rpair: 0,
                rindex: 0,
                reads: 0,
                floor: 0,
                last_read: 0,
            };
            let mut seen = HashSet::new();
            let mut stack = vec![init.clone()];
            seen.insert(init);
            while let Some(s) = stack.pop() {
                for n in [writer_step(&s, v), reader_step(&s, v)]
                    .into_iter()
                    .flatten()
                {
                    if let Some(e) = violation(&n, &s) {
                        return Err(e);
                    }
                    if seen.insert(n.clone()) {
                        stack.push(n);
                    }
                }
            }
            Ok(seen.len())
        }

        #[test]
        fn simpson_is_safe_in_every_interleaving() {
            let states = check(Variant::Simpson);
            assert!(states.is_ok(), "{states:?}");
            // Sanity: the exploration is not trivially small.
            assert!(states.unwrap_or(0) > 1000, "{states:?}");
            // Skipping an announcement that changes nothing visits the
            // same states.
            assert_eq!(check(Variant::SkipSameAnnounce), states);
        }

        #[test]
        fn broken_variants_are_caught() {
            for v in [
                Variant::NoAnnounce,
                Variant::SameIndex,
                Variant::LoadBeforeAnnounce,
            ] {
                assert_eq!(
                    check(v).err(),
                    Some("the reader and the writer access the same slot")
                );
            }
        }
    }
}
