//! The board's log queue: the loop formats its lines into a fixed ring buffer and the USART's
//! transmit interrupt sends them, so a log line never blocks the control period (at 115200
//! baud a 60-byte line takes 5.2 ms: written byte by byte from the loop it would miss two
//! periods, and with a long supervisor state three, tripping `Overrun`). When the queue is
//! full the rest of the line is dropped and counted. Pure (host-tested in
//! `host-tests/tests/board_pure.rs`); the interrupt and the lock are in `main.rs`.

/// A byte ring buffer of `N` bytes.
#[derive(Clone, Debug)]
pub struct TxQueue<const N: usize> {
    buf: [u8; N],
    head: usize,
    len: usize,
    dropped: u64,
}

impl<const N: usize> Default for TxQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> TxQueue<N> {
    /// An empty queue.
    pub const fn new() -> Self {
        TxQueue {
            buf: [0; N],
            head: 0,
            len: 0,
            dropped: 0,
        }
    }

    /// Appends what fits of `bytes`; counts the rest as dropped. Returns the bytes taken.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        let mut taken = 0;
        for &b in bytes {
            if self.len == N {
                break;
            }
            if let Some(slot) = self.buf.get_mut((self.head + self.len) % N) {
                *slot = b;
                self.len += 1;
                taken += 1;
            }
        }
        self.dropped += (bytes.len() - taken) as u64;
        taken
    }

    /// The oldest byte, removed.
    pub fn pop(&mut self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        let b = self.buf.get(self.head).copied();
        self.head = (self.head + 1) % N;
        self.len -= 1;
        b
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is waiting.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes dropped so far because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}
