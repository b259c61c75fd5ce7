//! The LET bounds on chains worked by hand.

use super::*;

/// A (T = 2) → B (T = 3), synchronous release (time in any unit).
/// A's job k reads at 2k and publishes at 2k + 2; B's job m reads at 3m
/// the last A value published at or before 3m and publishes at 3m + 3.
///
/// | A job (read) | visible   | B jobs reading it | B publishes |
/// |--------------|-----------|-------------------|-------------|
/// | 0 (0)        | [2, 4)    | m = 1 (3)         | 6           |
/// | 1 (2)        | [4, 6)    | none: lost        |             |
/// | 2 (4)        | [6, 8)    | m = 2 (6)         | 9           |
/// | 3 (6)        | [8, 10)   | m = 3 (9)         | 12          |
/// | 4 (8)        | [10, 12)  | none: lost        |             |
/// | 5 (10)       | [12, 14)  | m = 4 (12)        | 15          |
///
/// and it repeats every H = 6. From the read: reaction = freshness =
/// max(6 − 0, 9 − 4, 12 − 6, 15 − 10) = 6. From the event after read k − 1
/// (at 2k − 2) to the first output of sample k or a newer one: k = 1 → 9 − 0,
/// k = 2 → 9 − 2, k = 3 → 12 − 4, k = 4 → 15 − 6, k = 5 → 15 − 8: 9. Event
/// freshness (samples that reach, from the read before): 9 − 2, 12 − 4,
/// 15 − 8: 8.
#[test]
fn two_tasks_synchronous_by_hand() {
    let chain = [LetTask { t: 2, phi: 0 }, LetTask { t: 3, phi: 0 }];
    let (lat, head_jobs) = exact(&chain, 1_000).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(
        lat,
        LetLatencies {
            reaction_read: 6,
            freshness_read: 6,
            reaction_event: 9,
            freshness_event: 8,
        }
    );
    assert!(head_jobs >= 4);
    // Any phasing: X = 2 + 2·3 = 8, F = 2·2 + 3 = 7: reaction ≤ 7,
    // freshness ≤ 7, from the event 2 + 8 = 10 and 2 + 7 = 9.
    let any = any_phasing(&[2, 3]).unwrap_or_else(|| panic!("empty"));
    assert_eq!(
        any,
        LetLatencies {
            reaction_read: 7,
            freshness_read: 7,
            reaction_event: 10,
            freshness_event: 9,
        }
    );
}

/// The same chain with B released at 1: B reads at 1, 4, 7, 10, 13 and
/// publishes 3 later. A job 0 (visible [2, 4)) is lost: at 4 A's job 1
/// publishes before B reads. Job 1 ([4, 6)) → B at 4, out at 7: 7 − 2 = 5.
/// Job 2 ([6, 8)) → B at 7, out at 10: 10 − 4 = 6. Job 3 ([8, 10)) is lost.
/// Job 4 ([10, 12)) → B at 10, out at 13: 5; job 5 → 16 − 10 = 6; it
/// repeats (H = 6): reaction = freshness = 6 from the read.
#[test]
fn offsets_decide_who_is_lost() {
    let chain = [LetTask { t: 2, phi: 0 }, LetTask { t: 3, phi: 1 }];
    let (lat, _) = exact(&chain, 1_000).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!((lat.reaction_read, lat.freshness_read), (6, 6));
    assert_eq!(carriers(&chain, 0), None);
    assert_eq!(carriers(&chain, 1), Some((7, 7)));
    assert_eq!(carriers(&chain, 2), Some((10, 10)));
    assert_eq!(carriers(&chain, 3), None);
}

#[test]
fn oversampling_consumer_carries_a_sample_several_times() {
    // A (T = 6) → B (T = 2): A job 0 is visible [6, 12): B jobs 3, 4, 5
    // read it and publish at 8, 10, 12: reaction 8, freshness 12.
    let chain = [LetTask { t: 6, phi: 0 }, LetTask { t: 2, phi: 0 }];
    assert_eq!(carriers(&chain, 0), Some((8, 12)));
    let (lat, _) = exact(&chain, 1_000).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!((lat.reaction_read, lat.freshness_read), (8, 12));
    // X = 6 + 2·2 = 10 > 8; F = 2·6 + 2 = 14 > 12.
    let any = any_phasing(&[6, 2]).unwrap_or_else(|| panic!("empty"));
    assert_eq!((any.reaction_read, any.freshness_read), (10, 14));
}

#[test]
fn limits_and_bad_chains() {
    assert_eq!(exact(&[], 10), Err(NoExact::BadChain));
    let chain = [LetTask { t: 7, phi: 0 }, LetTask { t: 11, phi: 0 }];
    assert!(matches!(exact(&chain, 3), Err(NoExact::TooManyJobs(_))));
}
