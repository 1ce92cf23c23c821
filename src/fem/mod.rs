//! Element kernels: shape functions, quadrature, internal force and tangent, surface
//! loads. Pure functions of element data: no MPI, no global numbering.

pub mod eas;
pub mod element;
pub mod hybrid;
pub mod kinematics;
pub mod mass;
pub mod reduced;
pub mod shape;
pub mod surface;
