//! When the core uses more than one thread. Loops over particles or pairs go parallel (rayon) only
//! inside a step of a system large enough to pay for it ([`with_warm_pool`], which keeps the
//! pool's other threads awake for the step) and only when the loop itself is long enough; every
//! parallel loop gives the same bits as the serial one: per-particle work is elementwise, pair
//! sums add each particle's terms in the serial loop's order ([`add_pairs_in_order`]), and
//! reductions are exact (max, first match). A run's result therefore does not depend on the
//! thread count.

/// Shortest loop worth splitting across threads (about 20 µs of per-particle work).
pub const MIN_PARALLEL_LEN: usize = 4096;

/// Chunk length for parallel loops over pairs: long enough that the hand-off stays small.
pub const CHUNK: usize = 1024;

/// Piece length of a parallel loop over `len` per-particle items: one contiguous share per
/// thread, split the same way in every loop of the step, so that each thread reads back from its
/// own cache the particles it wrote in the loop before (with finer pieces rayon hands them out by
/// timing, and half of them come from the other core). Two threads' loops over particles split
/// where the step's [`Balance`] puts them instead ([`split_of`]).
pub fn share(len: usize) -> usize {
    len.div_ceil(rayon::current_num_threads()).max(CHUNK)
}

thread_local! {
    /// Set on the thread running a step inside [`with_warm_pool`].
    static WARM: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// The step's split between two threads and what its shares took so far (on the thread
    /// running the step, inside [`with_warm_pool`]).
    static BALANCE: std::cell::Cell<Balance> = const { std::cell::Cell::new(Balance::EVEN) };
}

/// Where the loops of a step split their items between two threads (the first share's
/// fraction), learnt from how long each share took. Equal shares of particles are not equal
/// work: the two halves of a box hold different neighbourhoods and contacts, and the two cores
/// of a shared machine do not run at one speed. The split moves towards equal times: after
/// [`Balance::SAMPLE`] of timed shares, half of the way to the fraction at which the two shares
/// would take equal times (each at its measured time per item). Any split gives the same bits (every parallel loop
/// does), so the balance decides only how long a run takes; with more than two threads the
/// shares stay equal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balance {
    /// The first share's fraction of the items.
    first: f64,
    /// Seconds and items of each of the two shares since the last move.
    time: [f64; 2],
    items: [f64; 2],
    /// Since the start: what the two shares of every timed loop took ([`ShareGaps`]).
    gaps: ShareGaps,
}

/// How far apart the two shares of the timed loops ended: the thread that ends first waits for
/// the other, so a step loses about half of each loop's gap (measured in
/// `reports/performance-history.md`, stage 35).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShareGaps {
    /// Two-share loops timed.
    pub loops: u64,
    /// Σ |end₀ − end₁| (s): the waits.
    pub gap: f64,
    /// Σ max(end₀, end₁) (s): the loops' times, each from its start to the later share's end.
    pub span: f64,
}

impl Default for Balance {
    fn default() -> Self {
        Self::EVEN
    }
}

impl Balance {
    /// Equal shares.
    pub const EVEN: Balance =
        Balance { first: 0.5, time: [0.0; 2], items: [0.0; 2], gaps: ShareGaps { loops: 0, gap: 0.0, span: 0.0 } };
    /// Timed share-seconds between two moves of the split.
    const SAMPLE: f64 = 0.2;
    /// The split is kept within these fractions.
    const LIMITS: (f64, f64) = (0.25, 0.75);
    /// Moves smaller than this are not made (each move makes the pair sums find their
    /// crossing pairs again).
    const STEP: f64 = 1.0 / 256.0;

    /// The first share at `first` of the items (within [`Balance::LIMITS`]).
    pub fn starting_at(first: f64) -> Self {
        Balance { first: first.clamp(Self::LIMITS.0, Self::LIMITS.1), ..Self::EVEN }
    }

    /// The first share's fraction of the items.
    pub fn first(&self) -> f64 {
        self.first
    }

    /// What the shares of the timed loops took since the start.
    pub fn gaps(&self) -> ShareGaps {
        self.gaps
    }

    /// Adds a two-share loop whose shares of `items` items ended `seconds` after its start.
    fn record(&mut self, [(end0, items0), (end1, items1)]: [(f64, usize); 2]) {
        self.time[0] += end0;
        self.time[1] += end1;
        self.items[0] += items0 as f64;
        self.items[1] += items1 as f64;
        let g = &mut self.gaps;
        (g.loops, g.gap, g.span) = (g.loops + 1, g.gap + (end0 - end1).abs(), g.span + end0.max(end1));
    }

    /// Moves the split once enough has been timed: the fraction f at which f c₀ = (1 − f) c₁
    /// (c, a share's time per item) is c₁/(c₀ + c₁); the split goes half way there.
    fn settle(&mut self) {
        if self.time[0] + self.time[1] < Self::SAMPLE || self.items.contains(&0.0) {
            return;
        }
        let (c0, c1) = (self.time[0] / self.items[0], self.time[1] / self.items[1]);
        let target = self.first + 0.5 * (c1 / (c0 + c1) - self.first);
        let target = (target / Self::STEP).round() * Self::STEP;
        if (target - self.first).abs() >= Self::STEP {
            self.first = target.clamp(Self::LIMITS.0, Self::LIMITS.1);
        }
        (self.time, self.items) = ([0.0; 2], [0.0; 2]);
    }
}

/// Whether a loop of `len` items should run in parallel: long enough, and inside a warm step
/// (outside one, or with one thread, the pool's threads would have to be woken for each loop).
#[inline]
pub fn worth_it(len: usize) -> bool {
    len >= MIN_PARALLEL_LEN && WARM.with(|w| w.get())
}

/// The buffers of an ordered parallel collection ([`collect_ordered`]), one per chunk, kept from
/// call to call: a collection run every step then allocates nothing once warm (allocating them
/// afresh, 1 024 items each, and handing out the copy in parallel cost 8 µs of a 50 µs neighbour
/// filter on two threads, dense 30 000 particles).
#[derive(Debug, Clone)]
pub struct Pieces<T>(Vec<Vec<T>>);

impl<T> Default for Pieces<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

/// Calls `f(k, out)` for k in 0..n, which may push items; the items end up in `out` in k order
/// (in parallel chunks when worth it, gathered in `pieces` and then copied into place).
pub fn collect_ordered<T: Copy + Default + Send + Sync>(
    n: usize,
    out: &mut Vec<T>,
    pieces: &mut Pieces<T>,
    f: impl Fn(usize, &mut Vec<T>) + Sync,
) {
    collect_ordered_ranges(n, out, pieces, |ks, out| ks.for_each(|k| f(k, out)))
}

/// [`collect_ordered`] with `f(ks, out)` called once per range of consecutive k (the chunks),
/// for a caller whose loop over k should be its own.
pub fn collect_ordered_ranges<T: Copy + Default + Send + Sync>(
    n: usize,
    out: &mut Vec<T>,
    pieces: &mut Pieces<T>,
    f: impl Fn(std::ops::Range<usize>, &mut Vec<T>) + Sync,
) {
    if !worth_it(n) {
        out.clear();
        f(0..n, out);
        return;
    }
    use rayon::prelude::*;
    let chunks = n.div_ceil(CHUNK);
    if pieces.0.len() < chunks {
        pieces.0.resize_with(chunks, Vec::new);
    }
    let parts = &mut pieces.0[..chunks];
    parts.par_iter_mut().enumerate().for_each(|(c, part)| {
        part.clear();
        f(c * CHUNK..n.min((c + 1) * CHUNK), part);
    });
    let total = parts.iter().map(Vec::len).sum();
    if !worth_it(total) {
        out.clear();
        parts.iter().for_each(|part| out.extend_from_slice(part));
        return;
    }
    // Resized from its last length (a buffer reused step after step hardly changes length), so
    // that only the difference is written serially before the parallel copy.
    out.resize(total, T::default());
    let mut slots = Vec::with_capacity(chunks);
    let mut rest = out.as_mut_slice();
    for part in parts.iter() {
        let (slot, tail) = rest.split_at_mut(part.len());
        slots.push(slot);
        rest = tail;
    }
    slots.into_par_iter().zip(&*parts).for_each(|(slot, part)| slot.copy_from_slice(part));
}

/// A sequence held in consecutive pieces, written in parallel and never joined (joining copied
/// every item once more: the 15-diameter pair list of the chained 100× state is 25 MB).
#[derive(Debug, Clone, Default)]
pub struct PieceList<T> {
    /// The pieces in use come first, none of them empty; each holds its items in a prefix (its
    /// length in `starts`) and stale slots after them, kept so that the next call need not
    /// initialise them again. The rest are kept for their capacity.
    pieces: Vec<Vec<T>>,
    /// `starts[p]`: the index of piece p's first item; one more entry, the length.
    starts: Vec<usize>,
    /// Items written per piece by the last [`PieceList::collect`].
    lengths: Vec<usize>,
}

impl<T: Send + Sync + Copy + Default> PieceList<T> {
    /// Calls `f(ks, slots)` on the ranges of consecutive k in 0..n (one per thread when worth
    /// it, otherwise one range); `f` writes its items for those k in k order into the first of
    /// `slots` (one per k: at most one item per k; their contents are stale) and returns how many
    /// it wrote. Slots are initialised only when a piece grows: zeroing them at every call took a
    /// fifth of the 15-diameter filter's time in the chained 100× state.
    pub fn collect(&mut self, n: usize, f: impl Fn(std::ops::Range<usize>, &mut [T]) -> usize + Sync) {
        use rayon::prelude::*;
        let chunks = if worth_it(n) { n.div_ceil(share(n)) } else { 1 };
        if self.pieces.len() < chunks {
            self.pieces.resize_with(chunks, Vec::new);
        }
        let size = n.div_ceil(chunks).max(1);
        let fill = |(c, piece): (usize, &mut Vec<T>)| {
            let ks = c * size..n.min((c + 1) * size);
            let len = ks.len();
            if piece.len() < len {
                piece.resize(len, T::default());
            }
            f(ks, &mut piece[..len])
        };
        if chunks > 1 {
            self.pieces[..chunks].par_iter_mut().enumerate().map(fill).collect_into_vec(&mut self.lengths);
        } else {
            self.lengths.clear();
            self.lengths.push(fill((0, &mut self.pieces[0])));
        }
        // Empty pieces moved behind the ones in use, in order (their buffers stay).
        self.starts.clear();
        self.starts.push(0);
        let mut used = 0;
        for (c, &len) in self.lengths.iter().enumerate() {
            if len > 0 {
                self.pieces.swap(used, c);
                self.starts.push(self.starts[used] + len);
                used += 1;
            }
        }
    }

    /// The list as one piece, which `fill` writes (into a buffer it must clear).
    pub fn fill_whole(&mut self, fill: impl FnOnce(&mut Vec<T>)) {
        if self.pieces.is_empty() {
            self.pieces.push(Vec::new());
        }
        fill(&mut self.pieces[0]);
        self.starts.clear();
        self.starts.push(0);
        if !self.pieces[0].is_empty() {
            self.starts.push(self.pieces[0].len());
        }
    }

    pub fn clear(&mut self) {
        self.starts.clear();
        self.starts.push(0);
    }

    pub fn len(&self) -> usize {
        self.starts.last().copied().unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The items, read in order.
    pub fn seq(&self) -> Pieced<'_, T> {
        let used = self.starts.len().saturating_sub(1);
        Pieced::Pieces { pieces: &self.pieces[..used], starts: &self.starts[..] }
    }
}

/// A sorted sequence as its readers see it: one slice, or the pieces of a [`PieceList`] (piece
/// p's items are the first `starts[p + 1] − starts[p]` of its buffer).
#[derive(Debug)]
pub enum Pieced<'a, T> {
    Whole(&'a [T]),
    Pieces { pieces: &'a [Vec<T>], starts: &'a [usize] },
}

impl<T> Clone for Pieced<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Pieced<'_, T> {}

impl<'a, T> Pieced<'a, T> {
    pub fn len(&self) -> usize {
        match self {
            Pieced::Whole(items) => items.len(),
            Pieced::Pieces { starts, .. } => starts.last().copied().unwrap_or(0),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The index of the first item for which `pred` is false (`pred` true on a prefix), as
    /// `slice::partition_point`.
    pub fn partition_point(&self, pred: impl Fn(&T) -> bool) -> usize {
        match *self {
            Pieced::Whole(items) => items.partition_point(pred),
            Pieced::Pieces { pieces, starts } => {
                let items = |p: usize| &pieces[p][..starts[p + 1] - starts[p]];
                // Pieces are not empty: the first piece whose last item fails holds the point.
                match (0..pieces.len()).find(|&p| items(p).last().is_some_and(|last| !pred(last))) {
                    Some(p) => starts[p] + items(p).partition_point(pred),
                    None => self.len(),
                }
            }
        }
    }

    /// Items `from..to` (from ≤ to), in order, as slices.
    pub fn slices(&self, from: usize, to: usize) -> impl Iterator<Item = &'a [T]> + Clone + 'a {
        let (whole, pieces, starts): (Option<&'a [T]>, &'a [Vec<T>], &'a [usize]) = match *self {
            Pieced::Whole(items) => (Some(&items[from..to.max(from)]), &[], &[]),
            Pieced::Pieces { pieces, starts } => (None, pieces, starts),
        };
        let first = starts.partition_point(|&s| s <= from).saturating_sub(1);
        let clip = move |(p, piece): (usize, &'a Vec<T>)| {
            let (s, e) = (starts[p], starts[p + 1]);
            let start = from.max(s);
            &piece[start - s..to.min(e).max(start) - s]
        };
        whole
            .into_iter()
            .chain(pieces.iter().enumerate().skip(first).take_while(move |&(p, _)| starts[p] < to).map(clip))
    }

    /// Items `from..to`, in order.
    pub fn range(&self, from: usize, to: usize) -> impl Iterator<Item = &'a T> + Clone + 'a {
        self.slices(from, to).flatten()
    }

    /// Every item, in order.
    pub fn iter(&self) -> impl Iterator<Item = &'a T> + Clone + 'a {
        self.range(0, self.len())
    }
}

/// `out[k] = f(k)` for k in 0..n (`out` resized to n), in the shares of [`for_each_share`]: each
/// thread writes the particles it reads and writes in the step's other loops.
pub fn map_ordered<T: Send + Clone + Default>(n: usize, out: &mut Vec<T>, f: impl Fn(usize) -> T + Sync + Send) {
    out.resize(n, T::default());
    for_each_share(&mut out[..], |first, share| share.iter_mut().enumerate().for_each(|(k, x)| *x = f(first + k)));
}

/// Per-particle slices, or tuples of them, that split at an index: the arguments of a loop run
/// in contiguous shares by [`for_each_share`].
pub trait Split: Sized + Send {
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    fn split_at(self, k: usize) -> (Self, Self);
}

impl<T: Sync> Split for &[T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        <[T]>::split_at(self, k)
    }
}

impl<T: Send> Split for &mut [T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        <[T]>::split_at_mut(self, k)
    }
}

macro_rules! split_tuple {
    ($($name:ident),+) => {
        impl<$($name: Split),+> Split for ($($name,)+) {
            fn len(&self) -> usize {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                let lengths = [$($name.len()),+];
                debug_assert!(lengths.iter().all(|&l| l == lengths[0]), "parts of one loop have one length");
                lengths[0]
            }
            fn split_at(self, k: usize) -> (Self, Self) {
                #[allow(non_snake_case)]
                let ($($name,)+) = self;
                #[allow(non_snake_case)]
                let ($($name,)+) = ($($name.split_at(k),)+);
                (($($name.0,)+), ($($name.1,)+))
            }
        }
    };
}
split_tuple!(A, B);
split_tuple!(A, B, C);
split_tuple!(A, B, C, D);
split_tuple!(A, B, C, D, E);
split_tuple!(A, B, C, D, E, F);
split_tuple!(A, B, C, D, E, F, G);

/// How [`for_each_share`] splits a loop of `len` items: (number of shares, items per share;
/// share k starts at item k × items per share, the last takes the rest). Two shares split where
/// the step's [`Balance`] puts them.
pub fn split_of(len: usize) -> (usize, usize) {
    if !worth_it(len) {
        return (1, len.max(1));
    }
    let share = share(len);
    match len.div_ceil(share).max(1) {
        2 => (2, ((len as f64 * BALANCE.with(|b| b.get().first)).round() as usize).clamp(1, len - 1)),
        shares => (shares, share),
    }
}

/// `parts` cut into the shares of [`split_of`], each with the index of its first item.
fn shares<S: Split>(parts: S) -> Vec<(usize, S)> {
    let len = parts.len();
    let (count, share) = split_of(len);
    let (mut pieces, mut rest, mut first) = (Vec::with_capacity(count), parts, 0);
    while pieces.len() + 1 < count {
        let (piece, tail) = rest.split_at(share);
        pieces.push((first, piece));
        (rest, first) = (tail, first + share);
    }
    pieces.push((first, rest));
    pieces
}

/// The one parallel-or-serial branch of per-particle loops: `f(first, parts)` on each share of
/// `parts` (one per thread inside a warm step of a large system, see [`share`]), or once on the
/// whole. Elementwise work gives the same bits either way.
pub fn for_each_share<S: Split>(parts: S, f: impl Fn(usize, S) + Sync + Send) {
    use rayon::prelude::*;
    // Serial loops, most of them, allocate nothing.
    if !worth_it(parts.len()) {
        return f(0, parts);
    }
    let shares = shares(parts);
    if shares.len() != 2 {
        return shares.into_par_iter().for_each(|(first, piece)| f(first, piece));
    }
    // Two shares: each timed from the loop's start to its own end (the other thread starts its
    // share a little later, when it takes it), for the balance.
    let started = std::time::Instant::now();
    let timed: Vec<(f64, usize)> = shares
        .into_par_iter()
        .map(|(first, piece)| {
            let len = piece.len();
            f(first, piece);
            (started.elapsed().as_secs_f64(), len)
        })
        .collect();
    BALANCE.with(|b| {
        let mut balance = b.get();
        balance.record([timed[0], timed[1]]);
        b.set(balance);
    });
}

/// Whether `test` holds on any share of `parts` (an exact reduction: the same answer serially).
pub fn any_share<S: Split>(parts: S, test: impl Fn(S) -> bool + Sync + Send) -> bool {
    use rayon::prelude::*;
    if !worth_it(parts.len()) {
        return test(parts);
    }
    shares(parts).into_par_iter().map(|(_, piece)| test(piece)).reduce(|| false, |a, b| a | b)
}

/// The largest of `f` over the shares of `parts`, at least 0 (an exact reduction: the same
/// answer serially).
pub fn max_over_shares<S: Split>(parts: S, f: impl Fn(S) -> f64 + Sync + Send) -> f64 {
    use rayon::prelude::*;
    if !worth_it(parts.len()) {
        return f(parts).max(0.0);
    }
    shares(parts).into_par_iter().map(|(_, piece)| f(piece)).reduce(|| 0.0, f64::max)
}

/// Σ over the pairs k (sorted by i, with i < j) of `both(k).0` into `out[i]` and `both(k).1`
/// into `out[j]`, each particle's terms added in pair order, as the loop
/// `for k { let (a, b) = both(k); out[i] += a; out[j] += b }` adds them, bit for bit. In shares
/// of particles when worth it: a share from `lo` > 0 first takes `earlier(lo, share)`, which
/// adds, in pair order, the parts for j alone of the pairs of rows before `lo` whose j is in the
/// share (those come first in its particles' serial sums; [`add_earlier_rows`] finds them by
/// scanning the rows), then walks its own rows, leaving the j beyond it to the shares after.
/// Nothing is buffered and no thread waits.
///
/// `four(k..k + 4)` is `both` of four consecutive items computed together (in SIMD lanes); the
/// terms are then added one by one, in order.
pub fn add_pairs_in_order<P: Sync, T: Copy + Send + std::ops::AddAssign>(
    out: &mut [T],
    pairs: Pieced<P>,
    ij: impl Fn(&P) -> (usize, usize) + Sync + Send,
    earlier: impl Fn(usize, &mut [T]) + Sync + Send,
    both: impl Fn(&P) -> (T, T) + Sync + Send,
    four: impl Fn([&P; 4]) -> [(T, T); 4] + Sync + Send,
) {
    debug_assert!(
        pairs.iter().zip(pairs.iter().skip(1)).all(|(a, b)| ij(a).0 <= ij(b).0)
            && pairs.iter().all(|q| ij(q).0 < ij(q).1),
        "pairs sorted by i, with i < j"
    );
    for_each_share(out, |lo, share| {
        let hi = lo + share.len();
        if lo > 0 {
            earlier(lo, share);
        }
        // The row's particle (share index) and its sum so far, held out of memory while its row
        // lasts: adding each term to memory made every pair wait for the store of the one
        // before. No other pair of the walk touches particle i meanwhile (every j is above i),
        // so the bits are those of adding in memory.
        let mut row: Option<(usize, T)> = None;
        let add = |share: &mut [T], row: &mut Option<(usize, T)>, q: &P, (a, b): (T, T)| {
            let (i, j) = ij(q);
            match row {
                Some((r, sum)) if *r == i - lo => *sum += a,
                _ => {
                    if let Some((r, sum)) = *row {
                        share[r] = sum;
                    }
                    let mut sum = share[i - lo];
                    sum += a;
                    *row = Some((i - lo, sum));
                }
            }
            if j < hi {
                share[j - lo] += b;
            }
        };
        let row_below = |bound: usize| pairs.partition_point(|q| ij(q).0 < bound);
        for slice in pairs.slices(row_below(lo), row_below(hi)) {
            let mut quads = slice.chunks_exact(4);
            for quad in &mut quads {
                let quad = [&quad[0], &quad[1], &quad[2], &quad[3]];
                quad.into_iter().zip(four(quad)).for_each(|(q, t)| add(share, &mut row, q, t));
            }
            for q in quads.remainder() {
                add(share, &mut row, q, both(q));
            }
        }
        if let Some((r, sum)) = row {
            share[r] = sum;
        }
    });
}

/// The `earlier` of [`add_pairs_in_order`] by scanning the pairs of the rows before the share
/// from `lo` from row `first_row` on (no row before it has a j from `lo` on) and adding
/// `second(k)`, the part for j alone, of those whose j is in the share.
pub fn add_earlier_rows<P, T: std::ops::AddAssign>(
    pairs: Pieced<P>,
    ij: impl Fn(&P) -> (usize, usize),
    first_row: usize,
    second: impl Fn(&P) -> T,
    lo: usize,
    share: &mut [T],
) {
    let hi = lo + share.len();
    let row_below = |bound: usize| pairs.partition_point(|q| ij(q).0 < bound);
    for slice in pairs.slices(row_below(first_row.min(lo)), row_below(lo)) {
        for q in slice {
            let j = ij(q).1;
            if (lo..hi).contains(&j) {
                share[j - lo] += second(q);
            }
        }
    }
}

/// Runs `f` (one step of a system of `len` particles) while the pool's other threads spin and
/// steal its parallel work, instead of falling asleep in the serial stretches between parallel
/// loops: waking a sleeping thread costs about 25 µs on the 2-core machines this runs on, more
/// than a loop over 30 000 particles takes. Without parallel work to share, just `f()`. Two
/// threads split the step's loops at `balance`, which then moves by what their shares took.
pub fn with_warm_pool<R: Send>(len: usize, balance: &mut Balance, f: impl FnOnce() -> R + Send) -> R {
    if len < MIN_PARALLEL_LEN || rayon::current_num_threads() < 2 {
        return f();
    }
    use std::sync::atomic::{AtomicBool, Ordering};
    /// Ends the other threads' spinning however the step ends (a step that panicked would
    /// otherwise leave the scope waiting for them forever).
    struct Finish<'a>(&'a AtomicBool);
    impl Drop for Finish<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    let done = AtomicBool::new(false);
    rayon::scope(|scope| {
        for _ in 1..rayon::current_num_threads() {
            scope.spawn(|_| {
                while !done.load(Ordering::Acquire) {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::hint::spin_loop();
                    }
                }
            });
        }
        let finish = Finish(&done);
        let was_warm = WARM.with(|w| w.replace(true));
        let was = BALANCE.with(|b| b.replace(*balance));
        let result = f();
        *balance = BALANCE.with(|b| b.replace(was));
        balance.settle();
        WARM.with(|w| w.set(was_warm));
        drop(finish);
        result
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The split waits for enough timed work, then moves half way to where the two shares'
    /// times per item would make equal times, and stays within its limits.
    #[test]
    fn the_balance_moves_half_way_to_equal_times() {
        let mut b = Balance::EVEN;
        // The second share's items take three times as long: equal times at a first share of 3/4.
        b.record([(0.025, 500), (0.075, 500)]);
        b.settle();
        assert_eq!(b.first(), 0.5, "0.1 s timed, half the sample: not yet");
        b.record([(0.025, 500), (0.075, 500)]);
        b.settle();
        assert_eq!(b.first(), 0.625, "half way from 1/2 to 3/4");
        for _ in 0..20 {
            b.record([(0.5, 900), (0.5, 100)]);
            b.settle();
        }
        assert_eq!(b.first(), Balance::LIMITS.1, "held at its limit");
        let mut even = Balance::starting_at(0.4);
        even.record([(0.1, 400), (0.1001, 600)]);
        even.settle();
        assert!((even.first() - 0.4).abs() < 1e-12, "a move below the step is not made");
    }

    /// The gaps add each loop's |end₀ − end₁| and later end, across the split's moves.
    #[test]
    fn share_gaps_add_the_waits_and_the_later_ends() {
        let mut b = Balance::EVEN;
        b.record([(0.25, 500), (0.5, 500)]);
        b.settle();
        b.record([(0.75, 400), (0.5, 600)]);
        let g = b.gaps();
        assert_eq!((g.loops, g.gap, g.span), (2, 0.5, 1.25));
        assert_ne!(b.first(), 0.5, "the split moved in between");
    }

    /// Reused buffers give the serial loop's items in order, whether the calls grow or shrink,
    /// and whether the items are many (parallel copy) or few (serial copy).
    #[test]
    fn ordered_collection_with_reused_pieces_equals_the_serial_loop() {
        let items = |k: usize, out: &mut Vec<u64>| {
            for copy in 0..k % 3 {
                out.push((k * 3 + copy) as u64);
            }
        };
        let rare = |k: usize, out: &mut Vec<u64>| {
            if k % 1000 == 7 {
                out.push(k as u64);
            }
        };
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let (mut out, mut pieces) = (vec![], Pieces::default());
        for n in [5000, 20_000, 4100, 9000, 4096] {
            for f in [&items as &(dyn Fn(usize, &mut Vec<u64>) + Sync), &rare] {
                let mut serial = vec![];
                (0..n).for_each(|k| f(k, &mut serial));
                pool.install(|| {
                    with_warm_pool(n, &mut Balance::default(), || collect_ordered(n, &mut out, &mut pieces, f))
                });
                assert_eq!(out, serial, "n = {n}");
            }
        }
        assert!(pieces.0.len() >= 20, "the buffers of the longest call are kept");
    }

    /// A share that panics inside a warm step ends the step with its panic (instead of leaving
    /// the pool's scope waiting for the spinning threads), and the pool then runs steps again.
    #[test]
    fn a_panic_in_a_warm_step_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let n = 3 * MIN_PARALLEL_LEN + 5;
        let mut out = vec![0u32; n];
        for panicking_share in [0, 1] {
            let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| {
                    with_warm_pool(n, &mut Balance::default(), || {
                        for_each_share(&mut out[..], |lo, _| assert_ne!(usize::from(lo > 0), panicking_share))
                    })
                })
            }));
            assert!(caught.is_err(), "share {panicking_share}'s panic reaches the caller");
        }
        pool.install(|| with_warm_pool(n, &mut Balance::default(), || for_each_share(&mut out[..], |_, s| s.fill(7))));
        assert!(out.iter().all(|&x| x == 7));
    }

    /// Pairs of random particles (sorted by i, i < j, rows of every length, particles in no
    /// pair): the shares of one, two and three threads add each particle's terms in the serial
    /// loop's order, so the sums are its bits. The terms are chosen so that the order matters.
    /// The pairs held in a [`PieceList`] read (items, partition points, ranges across pieces)
    /// and sum as the same pairs in one slice.
    #[test]
    fn ordered_pair_sums_equal_the_serial_loop_on_any_thread_count() {
        // Not a multiple of 2 or 3: the last share is shorter than the others.
        let n = 3 * MIN_PARALLEL_LEN + 17;
        // Particle numbers from a 64-bit mix (SplitMix64's finaliser), so that rows and their
        // partners fall in every share.
        let particle = |k: u64| {
            let mut z = k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) % n as u64) as usize
        };
        let mut pairs: Vec<(usize, usize)> =
            (0..40 * n as u64).map(|k| (particle(2 * k), particle(2 * k + 1))).filter(|(i, j)| i < j).collect();
        pairs.sort_unstable();
        // The rows reaching a share are bounded as a Verlet list bounds them: the lowest i of a
        // pair with j at or beyond it.
        let both = |&(i, j): &(usize, usize)| (1.0 / (1.0 + (i * 7 + j) as f64), -3.0e5 / (1.0 + (j * 3 + i) as f64));
        let second = |q: &(usize, usize)| both(q).1;
        // Four at a time (as a list's kernel in SIMD lanes) and one by one at the end of a
        // slice: both ways must add the same terms in the same order.
        let four = |q: [&(usize, usize); 4]| q.map(both);
        let mut reaching = vec![usize::MAX; n + 1];
        for &(i, j) in &pairs {
            reaching[j] = reaching[j].min(i);
        }
        for j in (0..n).rev() {
            reaching[j] = reaching[j].min(reaching[j + 1]);
        }
        let reach = |lo: usize| reaching[lo];
        let mut serial = vec![0.1; n];
        for q in &pairs {
            let (a, b) = both(q);
            serial[q.0] += a;
            serial[q.1] += b;
        }
        // The same pairs held in pieces, some empty (left out of the list), as a filter writes
        // them into slots left from a longer list.
        let mut pieced = PieceList::default();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        pool.install(|| {
            with_warm_pool(pairs.len(), &mut Balance::default(), || {
                // First every pair, then fewer: the slots the first call wrote and the second
                // does not must not show through.
                let all = |_: &(usize, usize)| true;
                let some = |q: &(usize, usize)| q.0 % 97 > 10 || q.0 > n / 2;
                for keep in [&all as &(dyn Fn(&(usize, usize)) -> bool + Sync), &some] {
                    pieced.collect(pairs.len(), |ks, slots: &mut [(usize, usize)]| {
                        let mut kept = 0;
                        for q in pairs[ks].iter().filter(|q| keep(q)) {
                            slots[kept] = *q;
                            kept += 1;
                        }
                        kept
                    })
                }
            })
        });
        let kept: Vec<(usize, usize)> = pairs.iter().copied().filter(|q| q.0 % 97 > 10 || q.0 > n / 2).collect();
        let seq = pieced.seq();
        assert!(matches!(seq, Pieced::Pieces { pieces, .. } if pieces.len() == 3), "three pieces");
        assert_eq!(seq.iter().copied().collect::<Vec<_>>(), kept);
        for bound in (0..n).step_by(37) {
            assert_eq!(seq.partition_point(|q| q.0 < bound), kept.partition_point(|q| q.0 < bound));
        }
        for (a, b) in [(0, 0), (0, kept.len()), (5, 5000), (1000, 1001), (4000, kept.len())] {
            assert_eq!(seq.range(a, b).copied().collect::<Vec<_>>(), kept[a..b]);
        }
        // Summed from the pieces, the serial loop's bits (rows bounded from 0: every share reads
        // the earlier pieces).
        let mut serial_kept = vec![0.1; n];
        for q in &kept {
            let (a, b) = both(q);
            serial_kept[q.0] += a;
            serial_kept[q.1] += b;
        }
        let mut out = vec![0.1; n];
        let earlier = |lo, share: &mut [f64]| add_earlier_rows(seq, |q| *q, 0, second, lo, share);
        pool.install(|| {
            with_warm_pool(n, &mut Balance::default(), || {
                add_pairs_in_order(&mut out, seq, |q| *q, earlier, both, four)
            })
        });
        assert!(out == serial_kept, "sums over pieces");
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for bound in [&reach as &(dyn Fn(usize) -> usize + Sync + Send), &|_| 0] {
                let mut out = vec![0.1; n];
                let whole = Pieced::Whole(&pairs);
                let earlier = |lo, share: &mut [f64]| add_earlier_rows(whole, |q| *q, bound(lo), second, lo, share);
                pool.install(|| {
                    with_warm_pool(n, &mut Balance::default(), || {
                        add_pairs_in_order(&mut out, whole, |q| *q, earlier, both, four)
                    })
                });
                assert!(out == serial, "{threads} threads");
            }
        }
    }
}
