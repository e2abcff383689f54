//! Instruction counts of the stepping kernels (gungraun, the successor of iai-callgrind):
//! stable where wall time is not, so a regression shows up even on a noisy machine.
//!
//! Needs valgrind and the runner (same version as the `gungraun` dev-dependency):
//!     cargo install gungraun-runner --version 0.20.0
//!     cargo bench --bench instructions
//! CI only compiles it (`cargo bench --no-run`).

mod common;

use grainchain_engine::Chain;
use grainchain_engine::Method;
use grainchain_engine::State;
use gungraun::{library_benchmark, library_benchmark_group, main};
use std::hint::black_box;

/// 1,000 all-moving grains of exponent `p`, advanced by 100 steps of dt = 1e-4.
fn setup(p: f64) -> (Chain, State) {
    common::all_moving(1000, p)
}

fn run(method: Method, input: (Chain, State)) -> u64 {
    let (chain, s0) = input;
    let prm = common::params(method);
    black_box(common::advance(&chain, &s0, &prm, 100.0 * prm.dt).steps)
}

#[library_benchmark]
#[bench::linear(args = (1.0), setup = setup)]
#[bench::hertz(args = (1.5), setup = setup)]
#[bench::quadratic(args = (2.0), setup = setup)]
#[bench::general(args = (2.5), setup = setup)]
fn verlet_100_steps(input: (Chain, State)) -> u64 {
    run(Method::Verlet, input)
}

#[library_benchmark]
#[bench::hertz(args = (1.5), setup = setup)]
fn blanes_moan4_100_steps(input: (Chain, State)) -> u64 {
    run(Method::BlanesMoan4, input)
}

#[library_benchmark]
#[bench::hertz(args = (1.5), setup = setup)]
fn gear5_100_steps(input: (Chain, State)) -> u64 {
    run(Method::Gear5, input)
}

#[library_benchmark]
#[bench::hertz(args = (1.5), setup = setup)]
fn dopri5_100_nominal_steps(input: (Chain, State)) -> u64 {
    run(Method::Dopri5, input)
}

library_benchmark_group!(
    name = kernels;
    benchmarks = verlet_100_steps, blanes_moan4_100_steps, gear5_100_steps, dopri5_100_nominal_steps
);

main!(library_benchmark_groups = kernels);
