//! The batch layer under `reproduce` and `study`: everything about running many simulations
//! that both commands share, and nothing about what they make of the results.
//!
//! - scene edits ([`SceneSource`]: a scene file read and parsed once, and the named
//!   transformations of the parse: run length, step, interface rule, the striker's
//!   perturbation; [`ContainerScene`]: a container scene with its parts named, every study
//!   dimension a method of it, the integrator decided in one place, [`Stepping::decide`]),
//! - jobs ([`Job`]: a checked scene, the regions to record by name, the snapshots to keep;
//!   [`run_job`] gives its [`RunData`]),
//! - the one thread pool with its progress bar ([`Pool`]),
//! - member files ([`write_member`], [`read_member`]): one finished job on disk.
//!
//! `reproduce` and `study` both build on this module and never import each other; the decay
//! analysis they share lives in [`grainchain_engine::analysis::decay`], the paper's numbers in
//! [`grainchain_engine::paper`].

mod container;
mod job;
pub mod mechanism;
mod members;
mod pool;
pub mod scenes;

pub use container::{ContainerScene, Part, Stepping};
pub use job::{run_job, Gauge, Job, Region, RunData, Snap, GAUGES};
pub use members::{
    member_status, read_member, write_member, BatchId, Member, MemberId, MemberMeta, MemberStatus,
    Shape,
};
pub use pool::Pool;
pub(crate) use scenes::{ContainerSource, SceneSource};
