//! Chain bounds under LET communication (`[system] communication = "let"`):
//! the one home of the LET rule in the analysis.
//!
//! Under Logical Execution Time (Kirsch and Sokolova 2012) job k of a task
//! with period T and offset φ reads at its release φ + k·T and publishes at
//! the end of its period φ + (k+1)·T, whenever the schedule ran it,
//! provided it completed by then (every R ≤ T, which `analyze` checks: a
//! chain with a task of unbounded response has no LET bound). At an instant
//! where a period ends and a job is released, the publish comes first. The
//! data flow is then a function of the periods and offsets alone, so:
//!
//! - with known offsets, the latencies are computed exactly, head job by
//!   head job over the hyperperiod (Becker et al., JSA 2017, the LET case of
//!   the job-level data propagation; Martinez, Sañudo and Bertogna, TCAD
//!   2018): [`exact`];
//! - with arbitrary offsets, the closed form of [`any_phasing`]
//!   (docs/analysis.md, "LET communication", derives both).

use rtpipe_model::{gcd, Nanos};

/// One task of a chain under LET: its period and release offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LetTask {
    /// Period T (positive).
    pub t: Nanos,
    /// Release offset φ (at least 0).
    pub phi: Nanos,
}

/// The four latencies of a chain, measured as the simulator measures them
/// (`rtpipe_joblog`): reaction and freshness from the head's read and from
/// the event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LetLatencies {
    /// Reaction from the head's read: first tail output of a sample.
    pub reaction_read: Nanos,
    /// Freshness from the head's read: last tail output of a sample.
    pub freshness_read: Nanos,
    /// Reaction from the event (just after the head read before).
    pub reaction_event: Nanos,
    /// Freshness from the event.
    pub freshness_event: Nanos,
}

/// Arbitrary offsets, periods `t` head first: the four latencies' bounds.
/// A sample read at r₁ is published at r₁ + T₁; each consumer's first job
/// to read it is released at or after the producer's publish and less
/// than T_c later, and publishes T_c after its release: the first output
/// comes less than X = T₁ + Σ_{i≥2} 2·T_i after the read. The last consumer
/// job to read it is released before the producer's next publish, less
/// than 2·T_p after the producer job's release: the last output comes less
/// than F = Σ_{i<n} 2·T_i + T_n after it. From the read: reaction ≤
/// min(X, F) (a sample that reaches the tail has its first output no later
/// than its last), freshness ≤ F. From the event (just after a head read):
/// the next read comes T₁ later and the immediate forward job chain from
/// it reaches the tail within X carrying that sample or a newer one, so
/// reaction ≤ T₁ + X (not T₁ + F: the newer sample's read is later);
/// freshness ≤ T₁ + F. Suprema: offsets approach X and F to within 1 ns
/// per link. `None` for an empty chain.
pub fn any_phasing(t: &[Nanos]) -> Option<LetLatencies> {
    let (&head, rest) = t.split_first()?;
    let (&tail, inner) = t.split_last()?;
    let x = head + rest.iter().map(|&v| 2 * v).sum::<Nanos>();
    let f = inner.iter().map(|&v| 2 * v).sum::<Nanos>() + tail;
    Some(LetLatencies {
        reaction_read: x.min(f),
        freshness_read: f,
        reaction_event: head + x,
        freshness_event: head + f,
    })
}

/// ⌈x / y⌉ for y > 0 and any sign of x.
fn ceil_div(x: i128, y: i128) -> i128 {
    -((-x).div_euclid(y))
}

/// The tail's (first, last) publish instants carrying head job k's
/// sample, `None` when it never reaches the tail (overwritten on the way).
/// The jobs carrying a sample form an interval [a, b] at every stage: a
/// consumer job m reads at φ_c + m·T_c the value of the last producer job
/// whose period ended at or before then.
fn carriers(chain: &[LetTask], k: i128) -> Option<(i128, i128)> {
    let (mut a, mut b) = (k, k);
    for w in chain.windows(2) {
        let (p, c) = (w[0], w[1]);
        let (pt, pphi, ct, cphi) = (p.t as i128, p.phi as i128, c.t as i128, c.phi as i128);
        // Job a's value is visible from its period's end; job b's until
        // the next period ends (exclusive: that publish comes first).
        let from = pphi + (a + 1) * pt;
        let until = pphi + (b + 2) * pt;
        let lo = ceil_div(from - cphi, ct).max(0);
        let hi = ceil_div(until - cphi, ct) - 1;
        if hi < lo {
            return None;
        }
        (a, b) = (lo, hi);
    }
    let n = chain.last()?;
    let (nt, nphi) = (n.t as i128, n.phi as i128);
    Some((nphi + (a + 1) * nt, nphi + (b + 1) * nt))
}

/// Why [`exact`] has no figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoExact {
    /// The chain is empty, a period is not positive or an offset negative.
    BadChain,
    /// The analysed span would hold more head jobs than the limit.
    TooManyJobs(u64),
    /// No sample ever reaches the tail.
    NoSampleReaches,
}

/// Known offsets: the exact latencies of the chain (the worst over every
/// sample of the infinite run), and the number of head jobs enumerated.
/// Head jobs released from the last offset on repeat with the hyperperiod
/// H (every consumer has started by the time it reads them), so the head
/// jobs released before max φ + H + T₁ cover every case; the from-event
/// reaction of a sample that never reaches the tail looks ahead to the next
/// one that does, up to one more H.
pub fn exact(chain: &[LetTask], limit: u64) -> Result<(LetLatencies, u64), NoExact> {
    let head = *chain.first().ok_or(NoExact::BadChain)?;
    if chain.iter().any(|x| x.t <= 0 || x.phi < 0) {
        return Err(NoExact::BadChain);
    }
    let mut h: i128 = 1;
    for x in chain {
        let t = x.t as i128;
        h = h / (gcd(h as Nanos, x.t) as i128).max(1) * t;
        if h > i128::from(Nanos::MAX) {
            return Err(NoExact::TooManyJobs(u64::MAX));
        }
    }
    let max_phi = chain.iter().map(|x| x.phi as i128).max().unwrap_or(0);
    let (ht, hphi) = (head.t as i128, head.phi as i128);
    let stamp = |k: i128| hphi + k * ht;
    // Head jobs analysed: released before max φ + H + T₁; then one more H
    // of look-ahead for the from-event reaction.
    let analysed = ceil_div(max_phi + h + ht - hphi, ht).max(1);
    let total = analysed + h / ht + 1;
    let jobs = u64::try_from(total).unwrap_or(u64::MAX);
    if jobs > limit {
        return Err(NoExact::TooManyJobs(jobs));
    }
    let reach: Vec<Option<(i128, i128)>> = (0..total).map(|k| carriers(chain, k)).collect();
    let mut worst = [None::<i128>; 4];
    let mut bump = |w: usize, v: i128| worst[w] = Some(worst[w].map_or(v, |x| x.max(v)));
    let mut next_reaching = None;
    for k in (0..total).rev() {
        if let Some((first, _)) = reach[k as usize] {
            next_reaching = Some(first);
        }
        if k >= analysed {
            continue;
        }
        if let Some((first, last)) = reach[k as usize] {
            bump(0, first - stamp(k));
            bump(1, last - stamp(k));
            if k > 0 {
                bump(3, last - stamp(k - 1));
            }
        }
        if let (true, Some(first)) = (k > 0, next_reaching) {
            bump(2, first - stamp(k - 1));
        }
    }
    let get = |w: usize| {
        worst[w]
            .and_then(|v| Nanos::try_from(v).ok())
            .ok_or(NoExact::NoSampleReaches)
    };
    let lat = LetLatencies {
        reaction_read: get(0)?,
        freshness_read: get(1)?,
        reaction_event: get(2)?,
        freshness_event: get(3)?,
    };
    Ok((lat, u64::try_from(analysed).unwrap_or(u64::MAX)))
}

#[cfg(test)]
mod tests;
