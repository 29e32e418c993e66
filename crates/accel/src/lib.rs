//! CPU data for volgraph, with no GPU in it: volumes and their loaders, generated test volumes,
//! transfer functions, the min/max block grid and transfer-function classification of
//! Krüger & Westermann 2003 §2.3, bricks and per-brick octrees of Ruijters & Vilanova 2006
//! §5 and §7, the orbit camera, and the f64 reference raycaster every GPU image is checked
//! against. The rendering conventions are in `docs/rendering_model.md`.

pub use volgraph_base::{cuts, input_file};

pub mod brick_leaves;
pub mod bricks;
pub mod camera;
pub mod chebyshev;
pub mod classify;
pub mod data_dir;
pub mod environment;
pub mod fusion;
pub mod generate;
pub mod histogram;
pub mod image_diff;
pub mod kd_split;
pub mod labels;
pub mod light;
pub mod load;
pub mod minmax;
pub mod mip;
pub mod octree;
pub mod organs;
pub mod path_trace;
pub mod probe;
pub mod progressive_error;
pub mod pyramid;
pub mod pyramid_file;
pub mod reference;
pub mod reslice;
pub mod srgb;
pub mod stats;
pub mod tooth;
pub mod transfer_function;
pub mod vessels;
pub mod volume;
pub mod volume_meta;
