//! [`Exchange`] over MPI (rsmpi over the system's Open MPI): the transport of
//! `volgraph render --distributed` under `mpirun`.

use mpi::traits::{Communicator, Destination, Equivalence, Source};

use crate::exchange::{Exchange, ExchangeError};

/// The processes of `MPI_COMM_WORLD`. Dropping it finalizes MPI.
pub struct MpiExchange {
    _universe: mpi::environment::Universe,
    world: mpi::topology::SimpleCommunicator,
}

impl MpiExchange {
    /// Initializes MPI (a process started without `mpirun` is a job of one); `None` when MPI
    /// was already initialized.
    pub fn initialize() -> Option<Self> {
        let universe = mpi::initialize()?;
        let world = universe.world();
        Some(Self { _universe: universe, world })
    }

    /// The processor (host) name, for messages.
    pub fn processor_name(&self) -> String {
        mpi::environment::processor_name().unwrap_or_default()
    }

    /// Ends every process of the job with `code` (after an error this process cannot report
    /// through [`crate::agree`]).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }
}

impl Exchange for MpiExchange {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn size(&self) -> usize {
        self.world.size() as usize
    }

    fn exchange_into(
        &mut self,
        outgoing: &[(usize, &[u8])],
        incoming: &mut [(usize, Vec<u8>)],
    ) -> Result<(), ExchangeError> {
        let world = &self.world;
        mpi::request::scope(|scope| {
            let requests: Vec<_> = outgoing
                .iter()
                .map(|&(to, bytes)| world.process_at_rank(to as i32).immediate_send(scope, bytes))
                .collect();
            for (from, buffer) in incoming.iter_mut() {
                // Probe for the length, then receive into the kept buffer: growing it is the
                // only allocation, and a buffer that shrinks keeps its pages.
                let (message, status) = world.process_at_rank(*from as i32).matched_probe();
                let len = status.count(u8::equivalent_datatype()) as usize;
                if buffer.len() < len {
                    buffer.resize(len, 0);
                } else {
                    buffer.truncate(len);
                }
                message.matched_receive_into(&mut buffer[..]);
            }
            for request in requests {
                request.wait();
            }
        });
        Ok(())
    }
}
