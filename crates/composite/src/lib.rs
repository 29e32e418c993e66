//! Sort-last compositing (`docs/scaling.md`): every process renders its box of the volume into a
//! premultiplied RGBA image, and the images are combined with the *over* operator in the
//! visibility order of the boxes. Two algorithms, as IceT offers them:
//!
//! - [`Compositor::direct_send`]: every process owns an equal tile of the image and receives from each
//!   other process that process's pixels in the tile — one round, N − 1 messages per process;
//! - [`Compositor::radix_k`] (Peterka et al. 2009): rounds over a factorization N = k₁·k₂·…; in a round,
//!   groups of kᵢ processes split the part of the image they share into kᵢ pieces and each
//!   composites one — fewer, larger messages than direct-send at scale (binary swap for k = 2).
//!
//! Both send only the non-empty pixel spans of an image ([`spans`]), and both finish with every
//! process holding one piece of the final image, which [`Compositor::gather`] collects on rank 0;
//! a [`Compositor`] keeps every buffer from frame to frame. The
//! transport is a trait ([`Exchange`]): threads in one process ([`LocalGroup`], for tests) or MPI
//! (`mpi` feature, [`mpi_exchange`]).

pub mod compositor;
pub mod direct_send;
pub mod exchange;
pub mod image;
#[cfg(feature = "mpi")]
pub mod mpi_exchange;
pub mod radix_k;
pub mod spans;

pub use compositor::Compositor;
pub use exchange::{Exchange, ExchangeError, LocalGroup, agree, all_gather, broadcast_from_root};
pub use image::{Layer, PixelRange, over_front_to_back};

/// What one process's compositing cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompositeStats {
    /// Bytes this process sent.
    pub bytes_sent: u64,
    /// Messages this process sent.
    pub messages: u64,
    /// Rounds of exchange.
    pub rounds: u32,
}
