//! Element kernels: shape functions, quadrature, internal force and tangent, surface
//! loads. Pure functions of element data: no MPI, no global numbering.

pub mod eas;
pub mod element;
pub mod error;
pub mod hybrid;
pub mod kernel;
pub mod kinematics;
pub mod mass;
pub mod measure;
pub mod patch;
pub mod reduced;
pub mod shape;
pub mod solid;
pub mod surface;
