//! The yearly phases, each a function over whole columns of the tree store (DESIGN.md).
pub mod climate;
pub mod growth;
pub mod light;
pub mod management;
pub mod mortality;
pub mod regen;
pub mod reproduction;
