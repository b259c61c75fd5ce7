//! Dense output: the plant's state at an instant inside a sub-step, from
//! the whole sub-step computed ahead (RK4's continuous extension), so a
//! sensor read between two grid points does not cut the grid's step in two.
//!
//! RK4's free interpolant (Hairer, Nørsett and Wanner, *Solving Ordinary
//! Differential Equations I*, II.6): with θ = (t − t₀)/h,
//! y(t₀ + θh) ≈ y₀ + h·(b₁(θ)k₁ + b₂(θ)k₂ + b₃(θ)k₃ + b₄(θ)k₄),
//! b₁ = θ − 3θ²/2 + 2θ³/3, b₂ = b₃ = θ² − 2θ³/3, b₄ = −θ²/2 + 2θ³/3,
//! third-order accurate (local error O(h⁴)) and equal to the step's own
//! end at θ = 1. Only views use it: what is integrated onward is always a
//! whole RK4 step (of the grid, or to an instant the inputs change at).

use super::{wrap_tau, State};

/// A sub-step computed ahead of the observed time: from `start_ns` over
/// `h_ns`, its stages and its (unnormalised) end.
#[derive(Debug, Clone)]
pub(super) struct Ahead {
    pub start_ns: u64,
    pub h_ns: u64,
    pub k: [State; 4],
    pub end: State,
}

impl Ahead {
    /// The state at `t_ns` inside the step (`start_ns < t_ns < start_ns +
    /// h_ns`) from the step's start `s0`, the attitude renormalised as a
    /// step's end is.
    pub fn state_at(&self, s0: &State, t_ns: u64) -> State {
        debug_assert!(self.start_ns < t_ns && t_ns < self.start_ns + self.h_ns);
        let h = self.h_ns as f64 * 1e-9;
        let th = (t_ns - self.start_ns) as f64 / self.h_ns as f64;
        let (th2, th3) = (th * th, th * th * th);
        let b1 = th - 1.5 * th2 + 2.0 / 3.0 * th3;
        let b23 = th2 - 2.0 / 3.0 * th3;
        let b4 = -0.5 * th2 + 2.0 / 3.0 * th3;
        let mut v = s0.plus_combination(&self.k, [h * b1, h * b23, h * b23, h * b4]);
        v.q = v.q.normalized();
        v
    }
}

/// The rotor angles at `t_ns` inside the step from `start_ns` (angles
/// `a0`, speeds `w0`) to speeds `w` then: the trapezoid the whole step's
/// bookkeeping uses, over the part of the step gone.
pub(super) fn angles_at(a0: &[f64; 4], w0: &[f64; 4], w: &[f64; 4], dt_s: f64) -> [f64; 4] {
    std::array::from_fn(|i| wrap_tau(a0[i] + 0.5 * dt_s * (w0[i] + w[i])))
}
