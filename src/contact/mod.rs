//! Rigid contact: shapes, walls and the contact laws (DESIGN.md, "Contact: the
//! formulation"). Kernels here are pure; the model's contact pass (`model::contact`)
//! loops over tracked nodes and the parallel layer never sees any of it.

pub mod law;
pub mod motion;
pub mod shape;
pub mod wall;
