//! OME-Zarr for volgraph: images stored as resolution pyramids of chunked, compressed arrays
//! (OME-NGFF 0.4 on Zarr v2, 0.5 on Zarr v3), the format microscopy, connectomics and micro-CT
//! volumes of tens to thousands of GB come in. Through the `zarrs` crate:
//!
//! - [`OmeZarr::open`]: the multiscales metadata (axes `t`, `c`, `z`, `y`, `x`, units, scale and
//!   translation per level) and each level's array, checked — sizes, chunk shapes, halving,
//!   data types, codecs — before a voxel is read ([`ngff`], [`store`]);
//! - [`OmeZarr::read_level`]: one level as a volume, chunk by chunk; a missing chunk drawn as
//!   the fill value with a warning naming it, an undecodable one with an error line, the rest
//!   still read ([`read`]);
//! - [`write_pyramid`]: any volume, streamed a slab at a time, as a pyramid halving to 64³ with
//!   every chunk's value range beside it, for skipping empty chunks unread ([`write`]);
//! - [`ZarrPyramid`]: the image as a `volgraph_accel::pyramid::PyramidSource`, read brick by
//!   brick through a bounded chunk cache for the ray-guided streaming raycaster ([`pyramid`]).

pub mod boxes;
mod error;
pub mod ngff;
pub mod pyramid;
pub mod read;
mod sample;
pub mod store;
pub mod write;

pub use boxes::StoreBoxes;
pub use error::ZarrError;
pub use pyramid::ZarrPyramid;
pub use read::{Pick, ReadLevel};
pub use store::{Level, OmeZarr};
pub use write::{InMemory, SlabSource, WriteOptions, WriteReport, write_pyramid};

/// Whether `path` looks like a Zarr store: a folder holding `zarr.json` (v3) or `.zgroup` (v2),
/// or named `*.zarr`.
pub fn is_zarr(path: &std::path::Path) -> bool {
    path.join("zarr.json").is_file()
        || path.join(".zgroup").is_file()
        || path.extension().is_some_and(|e| e.eq_ignore_ascii_case("zarr"))
}
