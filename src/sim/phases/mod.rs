//! The yearly phases, each a function over whole columns of the tree store (DESIGN.md).
pub mod growth;
pub mod light;
pub mod mortality;
pub mod regen;
pub mod reproduction;
