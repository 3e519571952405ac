//! # Sylva
//!
//! Forests at terrain scale. A real elevation model becomes living conditions
//! ([`terrain`], [`conditions`]); species from an editable library ([`species`]) seed, grow,
//! compete and die ([`sim`]); every tree keeps a branching skeleton ([`structure`]); thousands of
//! trees are rendered with level of detail into stills and timelapses ([`render`]).
//!
//! The core (terrain, conditions, species, sim, structure) is pure: it knows nothing of GPUs,
//! windows or files beyond its loaders. See `ARCHITECTURE.md`.
#![warn(missing_docs)]

pub mod climate;
pub mod conditions;
pub mod edit;
pub mod error;
pub mod grid;
pub mod gpkg;
pub mod gui;
pub mod job;
pub mod mesh;
pub mod obstacle;
pub mod output;
pub mod render;
pub mod rng;
pub mod sim;
pub mod species;
pub mod structure;
pub mod sun;
pub mod terrain;
pub mod view;

pub use error::{Error, Result};
