//! The streamed render's rows of tiles. Outside IAA they are traced
//! without a barrier ([`Frame::stream_rows`]):
//! every worker takes the next tile in image order, and whichever worker
//! finishes the last missing tile of the next row hands the finished rows
//! to the sink, in order, while the others trace on.
//!
//! It replaced stripes of four rows traced as one parallel pass, each
//! waiting for its slowest tile (and anti-aliased in a second pass):
//! at 16 threads a stripe of a 1024-wide image is eight tiles a worker,
//! and a slow tile (shadows, a cluster of objects) left the others idle.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

use super::{Frame, edges_of, tile_row};
use crate::render::aa::{NeighbourTiles, TileEdges};
use crate::render::context::stats::RenderStats;
use crate::render::tile::TileOut;
use crate::render::{RenderError, TILE};

/// The tiles traced and not yet handed on, and how far the hand-over is.
struct Shelf {
    /// One slot per tile of the image, in image order.
    tiles: Vec<Option<TileOut>>,
    /// Rows of tiles handed on.
    rows_out: usize,
    /// The sink failed or the render was cancelled: workers stop.
    stop: bool,
}

impl Shelf {
    /// Takes out the next row to hand on (`per_row` tiles) and its index,
    /// if all of it is traced.
    fn take_next_row(&mut self, per_row: usize) -> Option<(usize, Vec<TileOut>)> {
        let r = self.rows_out;
        let row = self.tiles.get_mut(r * per_row..(r + 1) * per_row)?;
        if self.stop || row.iter().any(Option::is_none) {
            return None;
        }
        Some((r, row.iter_mut().filter_map(Option::take).collect()))
    }

    /// Whether the next row to hand on is all traced.
    fn next_row_ready(&self, per_row: usize) -> bool {
        let r = self.rows_out;
        let row = self.tiles.get(r * per_row..(r + 1) * per_row);
        !self.stop && row.is_some_and(|row| row.iter().all(Option::is_some))
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
    /// Signalled whenever the shelf's `rows_out` or `stop` changes.
    moved: Condvar,
    emitter: Mutex<Emitter<F, E>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl<F, E> Handover<'_, F, E>
where
    F: FnMut(Vec<TileOut>, u32) -> Result<(), E>,
{
    /// Waits until tile `i` lies within `ahead` rows of the first row not
    /// handed on; false once the workers are to stop. The first row not
    /// handed on is never waited for, so a worker on it always moves.
    fn wait_for_room(&self, i: usize, ahead: usize) -> bool {
        let mut s = lock(&self.shelf);
        while !s.stop && i / self.per_row >= s.rows_out + ahead {
            s = self.moved.wait(s).unwrap_or_else(PoisonError::into_inner);
        }
        !s.stop
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
    /// Traces every tile (outside IAA) and anti-aliases it, and calls
    /// `on_row(tiles, y0)` with each row of tiles, top to bottom, once all
    /// of it is traced. Workers run at most `ahead` rows of tiles past the
    /// first row not yet handed on, so memory holds that many rows.
    pub(super) fn stream_rows<E: Send + From<RenderError>>(
        &self,
        ahead: usize,
        done: &AtomicUsize,
        on_row: impl FnMut(Vec<TileOut>, u32) -> Result<(), E> + Send,
    ) -> Result<(), E> {
        let (w, h) = (self.opts.width, self.opts.height);
        let tiles = super::tiles(w, h);
        let hand = Handover {
            tiles: &tiles,
            per_row: w.div_ceil(TILE) as usize,
            shelf: Mutex::new(Shelf {
                tiles: (0..tiles.len()).map(|_| None).collect(),
                rows_out: 0,
                stop: false,
            }),
            moved: Condvar::new(),
            emitter: Mutex::new(Emitter {
                on_row,
                error: None,
            }),
        };
        let next = AtomicUsize::new(0);
        self.pool.broadcast(|_| {
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= tiles.len() || !hand.wait_for_room(i, ahead) {
                    break;
                }
                if self.cancelled() {
                    hand.fail(RenderError::Cancelled.into());
                    break;
                }
                let mut out = self.trace_tile(tiles[i]);
                self.anti_alias_one(&mut out, NeighbourTiles::default(), done, tiles.len());
                lock(&hand.shelf).tiles[i] = Some(out);
                hand.drain(self);
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

/// Hands rows of traced tiles to the bands and the sink: the time it
/// took, ms.
pub(super) type EmitRows<'a, E> =
    dyn FnMut(Vec<(Vec<TileOut>, u32)>, &mut RenderStats) -> Result<f64, E> + Send + 'a;

impl Frame<'_> {
    /// IAA's streamed render: the base render runs one row of tiles ahead
    /// (the shadow-edge rule reads the next row's samples), a row at a
    /// time, and each row is written while the next is traced. Returns
    /// the time spent writing, ms.
    pub(super) fn stream_look_ahead<E: Send + From<RenderError>>(
        &self,
        done: &AtomicUsize,
        emit: &mut EmitRows<'_, E>,
        stats: &mut RenderStats,
    ) -> Result<f64, E> {
        let (w, h) = (self.opts.width, self.opts.height);
        let total = super::tiles(w, h).len();
        let rows: Vec<u32> = (0..h).step_by(TILE as usize).collect();
        let mut output_ms = 0.0;
        // The row traced, not yet made a band and written.
        let mut pending: Vec<(Vec<TileOut>, u32)> = Vec::new();
        let mut above: Vec<TileEdges> = Vec::new();
        let mut current = Some(self.pool.install(|| self.trace(&tile_row(w, h, 0))));
        for (r, &y0) in rows.iter().enumerate() {
            if self.cancelled() {
                return Err(RenderError::Cancelled.into());
            }
            let (traced, written) = self.pool.install(|| {
                rayon::join(
                    || {
                        let mut outs = current
                            .take()
                            .unwrap_or_else(|| self.trace(&tile_row(w, h, y0)));
                        let next = rows.get(r + 1).map(|&y| self.trace(&tile_row(w, h, y)));
                        let edges: Vec<TileEdges> = outs.iter().map(edges_of).collect();
                        let below: Vec<TileEdges> =
                            next.iter().flat_map(|n| n.iter().map(edges_of)).collect();
                        let beside = |i: usize| NeighbourTiles {
                            above: above.get(i),
                            below: below.get(i),
                            left: i.checked_sub(1).and_then(|k| edges.get(k)),
                            right: edges.get(i + 1),
                        };
                        self.anti_alias_tiles(&mut outs, beside, done, total);
                        ((outs, y0), next, edges)
                    },
                    || emit(std::mem::take(&mut pending), stats),
                )
            });
            output_ms += written?;
            let (row, next, edges) = traced;
            above = edges;
            current = next;
            self.release_groups_above(y0 + TILE);
            pending = vec![row];
        }
        Ok(output_ms + emit(pending, stats)?)
    }
}
