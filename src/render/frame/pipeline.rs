//! The streamed render's tiles, traced without a barrier
//! ([`Frame::stream_rows`]): every worker takes the next job in image
//! order, and whichever worker finishes the last missing tile of the next
//! row hands the finished rows to the sink, in order, while the others
//! work on. A tile's jobs are its base render and its anti-aliasing; IAA's
//! reads the base samples just outside the tile (`aa::NeighbourTiles`), so
//! it waits for the four neighbours' base renders, and meanwhile workers
//! take base renders further on.
//!
//! It replaced stripes of rows traced as one parallel pass each, every
//! stripe waiting for its slowest tile and anti-aliased in a second pass
//! (IAA a row at a time): at 16 threads a four-row stripe of a 1024-wide
//! image is eight tiles a worker, and a slow tile (shadows, a cluster of
//! objects) left the others idle.

use std::sync::atomic::AtomicUsize;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};

use super::{Frame, edges_of};
use crate::render::aa::{Aa, NeighbourTiles, TileEdges};
use crate::render::tile::TileOut;
use crate::render::{RenderError, TILE};

/// Where one tile stands (a tile's output boxed: the image's slots are
/// held from the start).
enum Slot {
    /// Not traced yet (or handed on).
    Empty,
    /// Base render done, waiting for its anti-aliasing (IAA).
    Base(Box<TileOut>),
    /// Being anti-aliased.
    Busy,
    /// Finished, waiting for its row to be handed on.
    Done(Box<TileOut>),
}

/// The tiles in flight and how far each stage is.
struct Shelf {
    /// One slot per tile of the image, in image order.
    slots: Vec<Slot>,
    /// The base samples on each tile's sides, once its base render is
    /// done (IAA only).
    edges: Vec<Option<Arc<TileEdges>>>,
    /// The next tile whose base render is to start.
    next_base: usize,
    /// The next tile whose anti-aliasing is to start (IAA only).
    next_aa: usize,
    /// Rows of tiles handed on.
    rows_out: usize,
    /// The sink failed or the render was cancelled: workers stop.
    stop: bool,
}

/// A worker's next job.
enum Job {
    /// The base render of tile `i` (and, outside IAA, its anti-aliasing).
    Base(usize),
    /// IAA on tile `i`'s base render, with its neighbours' sides.
    Aa(usize, Box<TileOut>, [Option<Arc<TileEdges>>; 4]),
}

impl Shelf {
    /// The shelf of an image of `n` tiles, nothing traced yet.
    fn new(n: usize) -> Shelf {
        Shelf {
            slots: (0..n).map(|_| Slot::Empty).collect(),
            edges: vec![None; n],
            next_base: 0,
            next_aa: 0,
            rows_out: 0,
            stop: false,
        }
    }

    /// Takes out the next row to hand on (`per_row` tiles) and its index,
    /// if all of it is finished.
    fn take_next_row(&mut self, per_row: usize) -> Option<(usize, Vec<TileOut>)> {
        if !self.next_row_ready(per_row) {
            return None;
        }
        let r = self.rows_out;
        let row = &mut self.slots[r * per_row..(r + 1) * per_row];
        let outs = row
            .iter_mut()
            .map(|s| match std::mem::replace(s, Slot::Empty) {
                Slot::Done(out) => *out,
                _ => unreachable!("a ready row holds finished tiles"),
            });
        Some((r, outs.collect()))
    }

    /// Whether the next row to hand on is all finished.
    fn next_row_ready(&self, per_row: usize) -> bool {
        let r = self.rows_out;
        let row = self.slots.get(r * per_row..(r + 1) * per_row);
        !self.stop && row.is_some_and(|row| row.iter().all(|s| matches!(s, Slot::Done(_))))
    }

    /// Tile `i`'s neighbours above, below, left and right, in a grid of
    /// `per_row` columns, where they exist.
    fn neighbours(&self, i: usize, per_row: usize) -> [Option<usize>; 4] {
        let n = self.slots.len();
        let col = i % per_row;
        [
            i.checked_sub(per_row),
            (i + per_row < n).then_some(i + per_row),
            (col > 0).then(|| i - 1),
            (col + 1 < per_row && i + 1 < n).then_some(i + 1),
        ]
    }

    /// The next job, if one can start: the next tile's IAA once its
    /// neighbours' base renders are done, else the next base render
    /// within `ahead` rows of the first row not handed on (the first such
    /// row is never held back, so a worker on it always moves). `Err`
    /// once nothing is left to start.
    fn next_job(&mut self, per_row: usize, ahead: usize, iaa: bool) -> Result<Option<Job>, ()> {
        let n = self.slots.len();
        if self.stop {
            return Err(());
        }
        let i = self.next_aa;
        if iaa && i < n && matches!(self.slots[i], Slot::Base(_)) {
            let near = self.neighbours(i, per_row);
            if near.iter().flatten().all(|&j| self.edges[j].is_some()) {
                let Slot::Base(out) = std::mem::replace(&mut self.slots[i], Slot::Busy) else {
                    unreachable!("matched above");
                };
                self.next_aa += 1;
                let sides = near.map(|j| j.and_then(|j| self.edges[j].clone()));
                return Ok(Some(Job::Aa(i, out, sides)));
            }
        }
        let b = self.next_base;
        if b < n && b / per_row < self.rows_out + ahead {
            self.next_base += 1;
            return Ok(Some(Job::Base(b)));
        }
        if b >= n && (!iaa || self.next_aa >= n) {
            return Err(());
        }
        Ok(None)
    }
}

/// The caller's row handler and its first error, held by the one worker
/// handing rows on.
struct Emitter<F, E> {
    on_row: F,
    error: Option<E>,
}

/// What the workers of [`Frame::stream_rows`] share.
struct Handover<'t, F, E> {
    /// The image's tiles in order: (x0, y0, w, h).
    tiles: &'t [(u32, u32, u32, u32)],
    per_row: usize,
    shelf: Mutex<Shelf>,
    /// Signalled whenever a job may have become ready: a base render
    /// done, a row handed on, the workers stopped.
    moved: Condvar,
    emitter: Mutex<Emitter<F, E>>,
}

/// Stops the other workers when the one holding it unwinds (a bug that
/// panics in a tile), so that none waits for a tile that never comes;
/// rayon then passes the panic on.
struct StopOnUnwind<'h>(&'h Mutex<Shelf>, &'h Condvar);

impl Drop for StopOnUnwind<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            lock(self.0).stop = true;
            self.1.notify_all();
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl<F, E> Handover<'_, F, E>
where
    F: FnMut(Vec<TileOut>, u32) -> Result<(), E>,
{
    /// Waits for the next job; None once there is none left (or the
    /// workers are to stop).
    fn wait_for_job(&self, ahead: usize, iaa: bool) -> Option<Job> {
        let mut s = lock(&self.shelf);
        loop {
            match s.next_job(self.per_row, ahead, iaa) {
                Ok(Some(job)) => return Some(job),
                Ok(None) => s = self.moved.wait(s).unwrap_or_else(PoisonError::into_inner),
                Err(()) => return None,
            }
        }
    }

    /// Stores what a job made and wakes the waiting workers.
    fn put(&self, i: usize, slot: Slot, edges: Option<TileEdges>) {
        let mut s = lock(&self.shelf);
        s.slots[i] = slot;
        if let Some(e) = edges {
            s.edges[i] = Some(Arc::new(e));
        }
        self.moved.notify_all();
    }

    /// Records the render's first error and stops the workers.
    fn fail(&self, e: E) {
        lock(&self.emitter).error.get_or_insert(e);
        lock(&self.shelf).stop = true;
        self.moved.notify_all();
    }

    /// Hands on every finished row, unless another worker is doing so. A
    /// row finished while the lock was held (its worker found it taken)
    /// is seen when it is let go, and handed on then.
    fn drain(&self, frame: &Frame<'_>) {
        let per_row = self.per_row;
        while let Ok(mut em) = self.emitter.try_lock() {
            loop {
                // The shelf's lock is let go before the row is handed on.
                let next = lock(&self.shelf).take_next_row(per_row);
                let Some((r, row)) = next else { break };
                let y0 = self.tiles[r * per_row].1;
                let handed = (em.on_row)(row, y0);
                frame.release_groups_above(y0 + TILE);
                let mut s = lock(&self.shelf);
                s.rows_out += 1;
                // The edges above the rows still to be anti-aliased are
                // read no more.
                for e in &mut s.edges[r.saturating_sub(1) * per_row..r * per_row] {
                    *e = None;
                }
                if let Err(e) = handed {
                    em.error.get_or_insert(e);
                    s.stop = true;
                }
                self.moved.notify_all();
            }
            drop(em);
            if !lock(&self.shelf).next_row_ready(per_row) {
                break;
            }
        }
    }
}

impl Frame<'_> {
    /// Traces every tile and anti-aliases it, and calls `on_row(tiles,
    /// y0)` with each row of tiles, top to bottom, once all of it is
    /// finished. Base renders run at most `ahead` rows of tiles past the
    /// first row not yet handed on (at least 2 with IAA, which reads the
    /// next row's), so memory holds that many rows.
    pub(super) fn stream_rows<E: Send + From<RenderError>>(
        &self,
        ahead: usize,
        done: &AtomicUsize,
        on_row: impl FnMut(Vec<TileOut>, u32) -> Result<(), E> + Send,
    ) -> Result<(), E> {
        let (w, h) = (self.opts.width, self.opts.height);
        let tiles = super::tiles(w, h);
        let iaa = matches!(self.aa, Aa::Iaa { .. });
        let hand = Handover {
            tiles: &tiles,
            per_row: w.div_ceil(TILE) as usize,
            shelf: Mutex::new(Shelf::new(tiles.len())),
            moved: Condvar::new(),
            emitter: Mutex::new(Emitter {
                on_row,
                error: None,
            }),
        };
        let ahead = if iaa { ahead.max(2) } else { ahead.max(1) };
        self.pool.broadcast(|_| {
            let _stop = StopOnUnwind(&hand.shelf, &hand.moved);
            while let Some(job) = hand.wait_for_job(ahead, iaa) {
                if self.cancelled() {
                    hand.fail(RenderError::Cancelled.into());
                    break;
                }
                match job {
                    Job::Base(i) if iaa => {
                        let out = self.trace_tile(tiles[i]);
                        let sides = edges_of(&out);
                        hand.put(i, Slot::Base(Box::new(out)), Some(sides));
                    }
                    Job::Base(i) => {
                        let mut out = self.trace_tile(tiles[i]);
                        self.anti_alias_one(&mut out, NeighbourTiles::default(), done, tiles.len());
                        hand.put(i, Slot::Done(Box::new(out)), None);
                        hand.drain(self);
                    }
                    Job::Aa(i, mut out, sides) => {
                        let [above, below, left, right] = sides.each_ref().map(Option::as_deref);
                        let beside = NeighbourTiles {
                            above,
                            below,
                            left,
                            right,
                        };
                        self.anti_alias_one(&mut out, beside, done, tiles.len());
                        hand.put(i, Slot::Done(out), None);
                        hand.drain(self);
                    }
                }
            }
        });
        let em = hand
            .emitter
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner);
        match em.error {
            Some(e) => Err(e),
            None => {
                let s = hand
                    .shelf
                    .into_inner()
                    .unwrap_or_else(PoisonError::into_inner);
                debug_assert_eq!(
                    s.rows_out * hand.per_row,
                    tiles.len(),
                    "every row is handed on"
                );
                Ok(())
            }
        }
    }
}
