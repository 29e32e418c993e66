//! The few CPU types volgraph's crates share that need no heavy dependency, so the graph
//! compiler can use them without the volume loaders (DICOM, JPEG 2000) or rayon that
//! `volgraph-accel` brings: a scene's cuts (crop box and clip planes, with the f64 reference of
//! what they keep) and bounded reading of the user's text inputs. `volgraph-accel` re-exports
//! both modules, so `volgraph_accel::cuts` and `volgraph_accel::input_file` name the same items.

pub mod cuts;
pub mod input_file;
