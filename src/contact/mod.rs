//! Contact kernels: rigid shapes and walls, small-sliding pairs between deformable
//! parts, and the contact laws they share (docs/src/design.md, "Contact: the formulation").
//! Kernels here are pure; the model's contributions (`model::walls`, `model::pairs`)
//! loop over tracked nodes and the parallel layer never sees any of it.

pub mod law;
pub mod mortar;
pub mod motion;
pub mod pair;
pub mod penalty;
pub mod search;
pub mod shape;
pub mod vec3;
pub mod wall;
