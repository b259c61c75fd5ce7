//! One link's sound terms at given periods, the least over the priority
//! orders a box of periods leaves open: what the box's affine bounds and
//! the split bound's pieces both evaluate at a corner.

use super::{least_deadlines, link_task, Order};
use crate::latency::{Case, SoundLink};
use rtpipe_model::{Nanos, Spec};

/// A task of a link: its index, its period and its response times (R, W).
pub(super) type At = (usize, Nanos, (Option<Nanos>, Option<Nanos>));

/// The least [`SoundLink`] of producer `p` and consumer `c` over `orders`
/// (the link's orders the box leaves open), each task at its least
/// deadline the box allows; `(distinct, head)` as [`SoundLink::new_in`]
/// takes them.
pub(super) fn least_link(
    spec: &Spec,
    order: &Order,
    orders: &[Option<Case>],
    (pi, tp, rp): At,
    (ci, tc, rc): At,
    (distinct, head): (bool, bool),
) -> SoundLink {
    let mut p = link_task(spec, tp, rp, pi);
    let mut c = link_task(spec, tc, rc, ci);
    least_deadlines(order, spec, pi, ci, &mut p, &mut c);
    SoundLink::least(
        orders
            .iter()
            .map(|&o| SoundLink::new_in(o, &p, &c, distinct, head)),
    )
}
