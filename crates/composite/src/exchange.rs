//! The transport compositing runs over, and the collectives the distributed renderer builds on
//! it: broadcasting the job, agreeing on success (so an error on one process ends every
//! process with that process's message instead of a hang).

use std::sync::mpsc::{Receiver, Sender, channel};

/// Why an exchange failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum ExchangeError {
    /// A peer went away (its process ended, its channel closed).
    #[error("rank {0} stopped answering")]
    PeerGone(usize),
    /// A message that does not decode.
    #[error("a malformed message: {0}")]
    Malformed(String),
    /// Another process failed; its message.
    #[error("rank {rank}: {message}")]
    Remote {
        /// The process that failed.
        rank: usize,
        /// Its error.
        message: String,
    },
    /// Every process failed with the same message: the job is wrong, not one process.
    #[error("{message}")]
    Everywhere {
        /// The error.
        message: String,
    },
}

/// Point-to-point messages between the processes of one job.
pub trait Exchange {
    /// This process's rank, `0..size`.
    fn rank(&self) -> usize;
    /// The number of processes.
    fn size(&self) -> usize;
    /// Sends each `(to, bytes)` of `outgoing` and receives one message from each `(from,
    /// buffer)` of `incoming` into its buffer (resized to the message; its capacity reused, so
    /// a caller that keeps its buffers allocates nothing from frame to frame). Every process of
    /// a round must call it with matching sends and receives; sends never wait for the matching
    /// receive to start.
    fn exchange_into(
        &mut self,
        outgoing: &[(usize, &[u8])],
        incoming: &mut [(usize, Vec<u8>)],
    ) -> Result<(), ExchangeError>;

    /// [`Exchange::exchange_into`] with new buffers: the messages from each rank of `from`, in
    /// that order.
    fn exchange(&mut self, outgoing: Vec<(usize, Vec<u8>)>, from: &[usize]) -> Result<Vec<Vec<u8>>, ExchangeError> {
        let sends: Vec<(usize, &[u8])> = outgoing.iter().map(|(to, bytes)| (*to, bytes.as_slice())).collect();
        let mut incoming: Vec<(usize, Vec<u8>)> = from.iter().map(|&r| (r, Vec::new())).collect();
        self.exchange_into(&sends, &mut incoming)?;
        Ok(incoming.into_iter().map(|(_, bytes)| bytes).collect())
    }
}

/// Every process's `mine`, by rank.
pub fn all_gather<E: Exchange + ?Sized>(ex: &mut E, mine: Vec<u8>) -> Result<Vec<Vec<u8>>, ExchangeError> {
    let (rank, size) = (ex.rank(), ex.size());
    let others: Vec<usize> = (0..size).filter(|&r| r != rank).collect();
    let outgoing = others.iter().map(|&r| (r, mine.clone())).collect();
    let mut received = ex.exchange(outgoing, &others)?.into_iter();
    Ok((0..size).map(|r| if r == rank { mine.clone() } else { received.next().unwrap_or_default() }).collect())
}

/// Rank 0's `message` on every process (the others pass anything, e.g. an empty vector).
pub fn broadcast_from_root<E: Exchange + ?Sized>(ex: &mut E, message: Vec<u8>) -> Result<Vec<u8>, ExchangeError> {
    if ex.rank() == 0 {
        let outgoing = (1..ex.size()).map(|r| (r, message.clone())).collect();
        ex.exchange(outgoing, &[])?;
        Ok(message)
    } else {
        Ok(ex.exchange(Vec::new(), &[0])?.pop().unwrap_or_default())
    }
}

/// Every process's outcome of a step, agreed: `Ok` on every process when every process
/// succeeded, [`ExchangeError::Everywhere`] when every process failed alike, else the lowest
/// failing rank's message on every process. Call it after every step
/// that can fail on one process only (reading its box, opening its GPU, rendering), so that no
/// process waits forever for one that gave up.
pub fn agree<E: Exchange + ?Sized, T>(ex: &mut E, outcome: Result<T, String>) -> Result<T, ExchangeError> {
    let mine = match &outcome {
        Ok(_) => Vec::new(),
        Err(message) => {
            let mut m = vec![1u8];
            m.extend(message.as_bytes());
            m
        }
    };
    let all = all_gather(ex, mine)?;
    if !all[0].is_empty() && all.iter().all(|m| *m == all[0]) {
        return Err(ExchangeError::Everywhere { message: String::from_utf8_lossy(&all[0][1..]).into_owned() });
    }
    if let Some((rank, failed)) = all.iter().enumerate().find(|(_, m)| !m.is_empty()) {
        return Err(ExchangeError::Remote { rank, message: String::from_utf8_lossy(&failed[1..]).into_owned() });
    }
    outcome.map_err(|message| ExchangeError::Remote { rank: ex.rank(), message })
}

/// Processes simulated by threads of one process: an [`Exchange`] per thread, over channels.
pub struct LocalGroup {
    rank: usize,
    size: usize,
    to: Vec<Sender<Vec<u8>>>,
    from: Vec<Receiver<Vec<u8>>>,
}

impl LocalGroup {
    /// `size` connected endpoints; give endpoint r to the thread of rank r.
    pub fn new(size: usize) -> Vec<LocalGroup> {
        // channels[src][dst]
        let mut senders: Vec<Vec<Option<Sender<Vec<u8>>>>> =
            (0..size).map(|_| (0..size).map(|_| None).collect()).collect();
        let mut receivers: Vec<Vec<Option<Receiver<Vec<u8>>>>> =
            (0..size).map(|_| (0..size).map(|_| None).collect()).collect();
        for (src, row) in senders.iter_mut().enumerate() {
            for (dst, slot) in row.iter_mut().enumerate() {
                let (tx, rx) = channel();
                *slot = Some(tx);
                receivers[dst][src] = Some(rx);
            }
        }
        senders
            .into_iter()
            .zip(receivers)
            .enumerate()
            .map(|(rank, (to, from))| LocalGroup {
                rank,
                size,
                to: to.into_iter().flatten().collect(),
                from: from.into_iter().flatten().collect(),
            })
            .collect()
    }
}

impl Exchange for LocalGroup {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn exchange_into(
        &mut self,
        outgoing: &[(usize, &[u8])],
        incoming: &mut [(usize, Vec<u8>)],
    ) -> Result<(), ExchangeError> {
        for &(to, bytes) in outgoing {
            self.to[to].send(bytes.to_vec()).map_err(|_| ExchangeError::PeerGone(to))?;
        }
        for (from, buffer) in incoming {
            *buffer = self.from[*from].recv().map_err(|_| ExchangeError::PeerGone(*from))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_failure_reaches_every_rank() {
        let results: Vec<Result<(), ExchangeError>> = std::thread::scope(|s| {
            let handles: Vec<_> = LocalGroup::new(3)
                .into_iter()
                .map(|mut ex| {
                    s.spawn(move || {
                        let outcome = if ex.rank() == 2 { Err("cannot read box".to_string()) } else { Ok(()) };
                        agree(&mut ex, outcome)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("thread")).collect()
        });
        for r in results {
            assert_eq!(r, Err(ExchangeError::Remote { rank: 2, message: "cannot read box".into() }));
        }
    }

    /// A job that fails alike everywhere (a volume too small for the ranks, a file no rank can
    /// read) is the job's error, not rank 0's.
    #[test]
    fn the_same_failure_everywhere_names_no_rank() {
        let results: Vec<Result<(), ExchangeError>> = std::thread::scope(|s| {
            let handles: Vec<_> = LocalGroup::new(3)
                .into_iter()
                .map(|mut ex| s.spawn(move || agree(&mut ex, Err::<(), _>("too small".to_string()))))
                .collect();
            handles.into_iter().map(|h| h.join().expect("thread")).collect()
        });
        for r in results {
            let e = r.expect_err("every rank failed");
            assert_eq!(e, ExchangeError::Everywhere { message: "too small".into() });
            assert_eq!(e.to_string(), "too small");
        }
    }
}
