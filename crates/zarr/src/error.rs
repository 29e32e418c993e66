//! Why a store cannot be read or written: each message names the store, the level or chunk and
//! the field, and says what would fix it.

use std::path::PathBuf;

/// An OME-Zarr problem.
#[derive(Debug, thiserror::Error)]
pub enum ZarrError {
    /// The path holds no Zarr group (neither `zarr.json` nor `.zgroup`).
    #[error("{path}: not a Zarr store (no zarr.json or .zgroup in it): give the folder of an OME-Zarr image")]
    NotZarr {
        /// The store.
        path: PathBuf,
    },
    /// A Zarr group without OME multiscales metadata.
    #[error(
        "{path}: a Zarr group without OME-NGFF \"multiscales\" metadata: volgraph reads OME-Zarr images \
         (NGFF 0.4 or 0.5); an image of a plate or a bare array is not one"
    )]
    NotOme {
        /// The store.
        path: PathBuf,
    },
    /// An NGFF version this reader does not know.
    #[error("{path}: OME-NGFF version \"{version}\" is not read here; volgraph reads 0.4 (Zarr v2) and 0.5 (Zarr v3)")]
    Version {
        /// The store.
        path: PathBuf,
        /// What the metadata says.
        version: String,
    },
    /// A metadata field that is missing or wrong.
    #[error("{path}: {field}: {problem}")]
    Metadata {
        /// The store.
        path: PathBuf,
        /// Where in the metadata (`multiscales[0].axes[2].unit`).
        field: String,
        /// What is wrong and how to fix it.
        problem: String,
    },
    /// A level's array that cannot be opened (a missing `zarr.json`, a codec not built in).
    #[error("{path}: level \"{level}\": {problem}")]
    Level {
        /// The store.
        path: PathBuf,
        /// The level's path in the store.
        level: String,
        /// What zarrs says, or what is wrong.
        problem: String,
    },
    /// A chunk that cannot be read or decoded.
    #[error("{path}: level \"{level}\", chunk (z, y, x) {}/{}/{}: {problem}", .chunk[0], .chunk[1], .chunk[2])]
    Chunk {
        /// The store.
        path: PathBuf,
        /// The level.
        level: String,
        /// The chunk's grid index, z, y, x.
        chunk: [u64; 3],
        /// What zarrs says.
        problem: String,
    },
    /// Writing a store failed.
    #[error("{path}: {problem}")]
    Write {
        /// The store.
        path: PathBuf,
        /// What failed.
        problem: String,
    },
    /// A level too large to read into memory whole.
    #[error(
        "{path}: level \"{level}\" is {shape} voxels ({mb} MiB), over the {limit_mb} MiB one read may hold; read a \
         coarser level (coarser levels: {coarser})"
    )]
    TooLarge {
        /// The store.
        path: PathBuf,
        /// The level.
        level: String,
        /// Its shape as text.
        shape: String,
        /// Its size.
        mb: u64,
        /// The limit.
        limit_mb: u64,
        /// The coarser levels' paths.
        coarser: String,
    },
}
