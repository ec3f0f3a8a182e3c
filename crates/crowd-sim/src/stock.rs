//! The crowd's stock of the buffers a walker needs only for some details or some time: a clip of
//! the size class its detail needs (when the source has several, [`ClipSource::clip_classes`]), a
//! foot lock while it is near, a seam transition while a seam runs. Lent to a walker when it needs
//! one and given back when its detail changes class, it goes far or the seam ends.
//!
//! The stock starts empty and grows only when more walkers need a buffer at once than ever before,
//! so the frame loop allocates only while the crowd warms up or reaches a new peak of near walkers,
//! and memory follows the most walkers near at once, not every walker that was ever near. The
//! stock is shared by every thread of the frame's pass without a lock: each kind is a bounded
//! lock-free queue (`crossbeam_queue::ArrayQueue`) whose slots are allocated with the crowd (16
//! bytes a slot: the buffers are boxed; [`spares`] slots a queue), and a buffer given back to a
//! full queue is freed (counted). Which buffer a walker gets depends on the order in
//! which threads reach the stock, but never what it shows: a seam transition is cleared and a foot
//! lock released before it is given back, and a clip is rebuilt before it is read, so the frames
//! are the same bytes on any thread count (the allocation counts are not).

use std::sync::atomic::{AtomicUsize, Ordering};

use crate::source::ClipSource;
use crossbeam_queue::ArrayQueue;
use lod_policy::{FootLock, SeamScratch, SeamTransition};

/// Slots of each of the stock's queues for a crowd of `walkers`: one per walker up to 4,096
/// walkers, then one per eight walkers. A queue holds the spares of one kind, which never outnumber
/// the walkers with joints or in a seam at the busiest moment so far; a crowd's LOD policy gives
/// joints to a few thousand walkers at most, so a larger crowd frees buffers only after more than an
/// eighth of it was near at once. (A slot per walker would cost 16 bytes a walker per queue, 96
/// with the model's six queues: 7 % of a million-walker crowd's memory.)
fn spares(walkers: usize) -> usize {
    walkers.min(4096).max(walkers / 8).max(1)
}

/// The crowd's stock (see the module documentation).
#[derive(Debug)]
pub(crate) struct Stock<C> {
    /// Spare clips of each size class ([`ClipSource::new_clip_of_class`]), not lent.
    clips: Vec<ArrayQueue<Box<C>>>,
    seams: ArrayQueue<Box<SeamTransition>>,
    locks: ArrayQueue<Box<FootLock>>,
    /// Allocator calls since the last [`Stock::take_allocations`]: buffers made because the stock
    /// had none to lend, and buffers freed because a queue was full.
    allocations: AtomicUsize,
}

impl<C> Stock<C> {
    /// An empty stock for a crowd of `walkers` whose source has `classes` clip size classes.
    pub fn new(walkers: usize, classes: usize) -> Stock<C> {
        let n = spares(walkers);
        Stock {
            clips: (0..classes).map(|_| ArrayQueue::new(n)).collect(),
            seams: ArrayQueue::new(n),
            locks: ArrayQueue::new(n),
            allocations: AtomicUsize::new(0),
        }
    }

    /// `class`, or the last class for one the source should not have given (checked in debug
    /// builds).
    fn class(&self, class: usize) -> usize {
        debug_assert!(
            class < self.clips.len(),
            "clip class {class} of {}",
            self.clips.len()
        );
        class.min(self.clips.len() - 1)
    }

    fn count(&self) {
        self.allocations.fetch_add(1, Ordering::Relaxed);
    }

    /// Keeps `x` in `queue`, or frees it (counted) when the queue is full.
    fn keep<T>(&self, queue: &ArrayQueue<T>, x: T) {
        if queue.push(x).is_err() {
            self.count();
        }
    }

    /// Makes spares so that `near` walkers at once can hold a clip of each class in `classes`, a
    /// foot lock and a seam transition, `lent` being what walkers hold now (clips of each class,
    /// then locks and seams); at most what the queues hold. Returns the buffers made (not counted
    /// as the frame loop's).
    pub fn reserve<S: ClipSource<Clip = C>>(
        &self,
        source: &S,
        near: usize,
        classes: impl Iterator<Item = usize>,
        lent: &Lent,
        seam: (usize, f32),
    ) -> usize {
        fn fill<T>(queue: &ArrayQueue<T>, want: usize, make: impl Fn() -> T) -> usize {
            let mut made = 0;
            while queue.len() < want && queue.push(make()).is_ok() {
                made += 1;
            }
            made
        }
        let mut made = 0;
        for class in classes.map(|c| self.class(c)) {
            made += fill(
                &self.clips[class],
                near.saturating_sub(lent.clips[class]),
                || Box::new(source.new_clip_of_class(class)),
            );
        }
        made + fill(&self.locks, near.saturating_sub(lent.locks), Box::default)
            + fill(&self.seams, near.saturating_sub(lent.seams), || {
                Box::new(SeamTransition::new(seam.0, seam.1))
            })
    }

    /// The allocator calls counted since the last call, and the count reset.
    pub fn take_allocations(&self) -> usize {
        self.allocations.swap(0, Ordering::Relaxed)
    }
}

/// What a crowd's walkers hold now of each kind the stock lends ([`Stock::reserve`]).
#[derive(Debug, Default)]
pub(crate) struct Lent {
    /// Clips of each size class.
    pub clips: [usize; crate::source::MAX_CLIP_CLASSES],
    pub locks: usize,
    pub seams: usize,
}

/// One chunk's access to the crowd's stock, with the seam scratch the chunk's kernel stage starts
/// seams with.
pub(crate) struct Lender<'a, C> {
    /// Scratch of the seams the chunk's kernel stage starts (holds nothing between seams).
    pub scratch: &'a mut SeamScratch,
    pub stock: &'a Stock<C>,
}

impl<C> Lender<'_, C> {
    /// Exchanges `clip` for a spare of the stock of `class` (one the stock lacks is made by the
    /// source), and returns the spare holding what `clip` held: give it back with
    /// [`Lender::give_clip`] under its class.
    #[cold]
    #[inline(never)]
    pub fn clip<S: ClipSource<Clip = C>>(
        &mut self,
        source: &S,
        clip: &mut C,
        class: usize,
    ) -> Box<C> {
        let stock = self.stock;
        let class = stock.class(class);
        let mut spare = stock.clips[class].pop().unwrap_or_else(|| {
            stock.count();
            Box::new(source.new_clip_of_class(class))
        });
        std::mem::swap(clip, &mut *spare);
        spare
    }

    /// Takes back a spare clip of `class`.
    #[cold]
    #[inline(never)]
    pub fn give_clip(&mut self, clip: Box<C>, class: usize) {
        let stock = self.stock;
        stock.keep(&stock.clips[stock.class(class)], clip);
    }

    /// A cleared seam transition over `pose_len` rows with the crowd's half-life (all of a crowd's
    /// have the same two).
    #[cold]
    #[inline(never)]
    pub fn seam(&mut self, pose_len: usize, halflife_s: f32) -> Box<SeamTransition> {
        self.stock.seams.pop().unwrap_or_else(|| {
            self.stock.count();
            Box::new(SeamTransition::new(pose_len, halflife_s))
        })
    }

    /// Takes back a seam transition (cleared here).
    #[cold]
    #[inline(never)]
    pub fn give_seam(&mut self, mut seam: Box<SeamTransition>) {
        seam.clear();
        self.stock.keep(&self.stock.seams, seam);
    }

    /// A released foot lock.
    #[cold]
    #[inline(never)]
    pub fn lock(&mut self) -> Box<FootLock> {
        self.stock.locks.pop().unwrap_or_else(|| {
            self.stock.count();
            Box::default()
        })
    }

    /// Takes back a foot lock (released here).
    #[cold]
    #[inline(never)]
    pub fn give_lock(&mut self, mut lock: Box<FootLock>) {
        lock.release();
        self.stock.keep(&self.stock.locks, lock);
    }
}
