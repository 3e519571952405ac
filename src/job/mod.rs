//! The main job's glue (`sylva run`, `sylva render`, `sylva timelapse`): from a run directory and
//! the site to pictures. The core modules stay independent of each other; this layer joins them.

pub mod inventory;
pub mod scene;
