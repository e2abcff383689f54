//! Shared set-up for the benchmarks: deterministic chains and a runner that advances a fresh copy
//! of the same state every iteration, so every iteration does exactly the same work.

#![allow(dead_code)]

use grainchain_engine::problems::GrainsInABox;
use grainchain_engine::Chain;
use grainchain_engine::State;
use grainchain_engine::Window;
use grainchain_engine::{self, IntegrationParams, Method, Stats};

/// A chain of `n` equal grains with law exponent `p` between two walls (the catalogue's
/// [`GrainsInABox`], eta = 5657), every grain moving with a deterministic velocity pattern
/// (contacts open and close all along the chain).
pub fn all_moving(n: usize, p: f64) -> (Chain, State) {
    let problem = GrainsInABox {
        p,
        eta: 5657.0,
        mass: 1.0,
        grains: n,
        velocities: (0..n)
            .map(|i| (i, 0.5 * (0.37 * i as f64).sin() + 0.01))
            .collect(),
    };
    let mut s = State::at_rest(n);
    for &(i, v) in &problem.velocities {
        s.v[i] = v;
    }
    (problem.chain().unwrap(), s)
}

/// Parameters used by the throughput benches: dt = 1e-4 (about 40 steps per contact time of the
/// all-moving state), dopri5 at rtol 1e-6.
pub fn params(method: Method) -> IntegrationParams {
    IntegrationParams {
        method,
        dt: 1e-4,
        rtol: 1e-6,
        atol: 1e-9,
        ..Default::default()
    }
}

/// Advance a copy of `s0` by `t`; returns the statistics (steps, evaluations).
pub fn advance(chain: &Chain, s0: &State, p: &IntegrationParams, t: f64) -> Stats {
    let n = chain.len();
    let mut integ = grainchain_engine::make_integrator(p, n);
    let mut state = s0.clone();
    let mut win = Window::seed(
        chain,
        &state.u,
        &state.v,
        p.skip_untouched,
        p.method.uses_islands(),
    );
    let mut stats = Stats::default();
    integ.init(chain, &state, &mut win, &mut stats);
    let t_end = state.t + t;
    integ
        .advance_to(chain, &mut state, &mut win, t_end, &mut stats)
        .unwrap();
    std::hint::black_box(&state.v);
    stats
}
