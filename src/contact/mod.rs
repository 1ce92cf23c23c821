//! Rigid contact: shapes, walls and the contact laws (DESIGN.md, Contact)

pub mod shape;
