//! Parallel loops that pay for threads only when there is enough work.
//!
//! The hot loops (column pieces, contact slots, kicks, list builds) run on the fork–join
//! [`super::team`]: the calling thread plus one worker per further core, each taking mostly
//! the same share of the work at every step, so that its data stays in its core's caches.
//! On two cores, work split among bevy's task pool (two threads plus the calling thread)
//! and handed out in arbitrary order ran the dense contact bed 1.3× faster than one
//! thread; on the team it runs 1.7–1.8× faster.
//!
//! Between jobs the workers spin for a short *block time* (as OpenMP runtimes do, e.g.
//! `KMP_BLOCKTIME`) instead of going to sleep at once: a step has several short jobs, and a
//! core that sleeps between them is halted, lent by the host to someone else and handed
//! back late (steal time). See [`super::ExecSettings`].

/// Default of [`super::ExecSettings::parallel_min`]. A team job starts in under a
/// microsecond, but on a small scene the second core gains nothing: its share is a few µs
/// of work and the particle data moves between the two cores' caches. On the dilute
/// contact benchmark on two threads (`scg bench dilute`, best of 3), 10^4 particles ran at
/// 7.4 ns per particle-step with a threshold of 16 384 and at 5.2 ns with this one; 10^3
/// particles ran at 8.6–8.8 ns with any threshold down to 256.
pub const PARALLEL_THRESHOLD: usize = 4096;

/// Below this many rows a per-particle pass runs on the calling thread
/// ([`super::ExecSettings::parallel_min`]; tests set it low so that small scenes go
/// through every parallel path). Results never depend on it.
pub fn parallel_min() -> usize {
    super::settings().parallel_min
}

/// Column slices that can be cut at a row: a slice, an optional slice, or a tuple of
/// those (all of one table, so of one length).
pub trait Split: Sized + Send {
    /// Rows (the shortest member; `usize::MAX` when there is no column).
    fn rows(&self) -> usize;
    /// Rows `..k` and `k..`.
    fn split_at(self, k: usize) -> (Self, Self);
}

impl<T: Send> Split for &mut [T] {
    fn rows(&self) -> usize {
        self.len()
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        self.split_at_mut(k)
    }
}

impl<T: Sync> Split for &[T] {
    fn rows(&self) -> usize {
        self.len()
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        <[T]>::split_at(self, k)
    }
}

impl<S: Split> Split for Option<S> {
    fn rows(&self) -> usize {
        self.as_ref().map_or(usize::MAX, S::rows)
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        match self {
            Some(s) => {
                let (a, b) = s.split_at(k);
                (Some(a), Some(b))
            }
            None => (None, None),
        }
    }
}

impl Split for () {
    fn rows(&self) -> usize {
        usize::MAX
    }
    fn split_at(self, _: usize) -> (Self, Self) {
        ((), ())
    }
}

/// The table rows a piece covers (global row numbers): cut like a column, so that a
/// piece of columns knows where it starts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rows(pub std::ops::Range<usize>);

impl Rows {
    /// The members of `sorted` (ascending row numbers) inside this piece.
    pub fn within<'a>(&self, sorted: &'a [u32]) -> &'a [u32] {
        let lo = sorted.partition_point(|&k| (k as usize) < self.0.start);
        let hi = sorted.partition_point(|&k| (k as usize) < self.0.end);
        &sorted[lo..hi]
    }

    /// Call `f` with the piece-local index of each row of this piece that `only` lists
    /// (ascending row numbers), or of every row when `only` is `None`.
    pub fn visit(&self, only: Option<&[u32]>, mut f: impl FnMut(usize)) {
        match only {
            Some(listed) => {
                (self.within(listed).iter()).for_each(|&k| f(k as usize - self.0.start))
            }
            None => (0..self.0.len()).for_each(f),
        }
    }
}

impl Split for Rows {
    fn rows(&self) -> usize {
        self.0.len()
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        let mid = self.0.start + k;
        (Rows(self.0.start..mid), Rows(mid..self.0.end))
    }
}

macro_rules! split_tuple {
    ($($t:ident $v:ident $a:ident $b:ident),+) => {
        impl<$($t: Split),+> Split for ($($t,)+) {
            fn rows(&self) -> usize {
                let ($($v,)+) = self;
                usize::MAX$(.min($v.rows()))+
            }
            fn split_at(self, k: usize) -> (Self, Self) {
                let ($($v,)+) = self;
                $(let ($a, $b) = $v.split_at(k);)+
                (($($a,)+), ($($b,)+))
            }
        }
    };
}
split_tuple!(A a a0 a1, B b b0 b1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1, G g g0 g1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1, G g g0 g1, H h h0 h1);

/// Rows per piece when columns are cut for the team.
const PIECE_ROWS: usize = 4096;

/// `body` on `columns` cut into pieces of `PIECE_ROWS` rows run on the team when there
/// are at least [`parallel_min`] rows, else on the whole at once. The pieces depend on
/// the row count only, and `body` must treat rows independently.
pub fn for_each_piece<P: Split>(columns: P, body: impl Fn(P) + Sync) {
    // Small pieces when the threshold is set low (tests), so that small scenes are cut too.
    let piece = PIECE_ROWS.min(parallel_min().div_ceil(2).max(64));
    run_pieces(columns, parallel_min(), piece, body);
}

/// Listed rows per piece of [`for_each_listed_piece`].
const LISTED_PIECE: usize = 128;

/// `body` on `columns` cut so that each piece holds about `LISTED_PIECE` of the `listed`
/// rows (ascending row numbers), the pieces on the team; `None`: [`for_each_piece`]. For
/// passes that visit only listed rows, each costly (a wall contact): cut by rows, a list
/// gathered at one end of the table would fall in one piece, on one thread. The cuts
/// depend on the list only, and `body` must treat rows independently.
pub fn for_each_listed_piece<P: Split>(
    columns: P,
    listed: Option<&[u32]>,
    body: impl Fn(P) + Sync,
) {
    let Some(listed) = listed else {
        return for_each_piece(columns, body);
    };
    let rows = columns.rows();
    let per = LISTED_PIECE.min(parallel_min().div_ceil(2).max(1));
    if rows == usize::MAX || listed.len() < 2 * per {
        body(columns);
        return;
    }
    // Each cut a listed row (ascending, distinct).
    let cuts = (per..listed.len())
        .step_by(per)
        .map(|k| (listed[k] as usize).min(rows));
    run_cut(columns, cuts, body);
}

/// How many times a plain per-particle update (a few ns) a row of
/// [`for_each_piece_heavy`] costs, roughly.
const HEAVY: usize = 64;

/// [`for_each_piece`] for passes whose rows cost about `HEAVY` times a plain update: a
/// particle tracked through a CFD mesh (locate, interpolate, drag: 0.2–1 µs). Those pay
/// for the team from [`parallel_min`]` / HEAVY` rows (64 by default), in pieces of
/// `rows / 8` (at least 32 rows, at most `PIECE_ROWS`): the cyclone's coarse-grained
/// runs, a few thousand particles, ran on one core under the plain threshold. The pieces
/// depend on the row count only, and `body` must treat rows independently.
pub fn for_each_piece_heavy<P: Split>(columns: P, body: impl Fn(P) + Sync) {
    let rows = columns.rows();
    let min = (parallel_min() / HEAVY).max(2);
    let piece = if rows == usize::MAX {
        PIECE_ROWS
    } else {
        (rows / 8).clamp(32.min(min.div_ceil(2)), PIECE_ROWS)
    };
    run_pieces(columns, min, piece, body);
}

/// `body` on `columns` in pieces of `piece` rows on the team when there are at least
/// `min` rows (and two pieces), else on the whole.
fn run_pieces<P: Split>(columns: P, min: usize, piece: usize, body: impl Fn(P) + Sync) {
    let rows = columns.rows();
    if rows == usize::MAX || rows < min || rows < 2 * piece {
        body(columns);
        return;
    }
    run_cut(columns, (piece..rows).step_by(piece), body);
}

/// `body` on the pieces of `columns` cut at the rows `cuts` (ascending, inside the
/// table), on the team.
fn run_cut<P: Split>(columns: P, cuts: impl Iterator<Item = usize>, body: impl Fn(P) + Sync) {
    let mut pieces = Vec::new();
    // `rest` starts at row `at`.
    let (mut rest, mut at) = (columns, 0);
    for cut in cuts {
        let (a, b) = rest.split_at(cut - at);
        pieces.push(Some(a));
        (rest, at) = (b, cut);
    }
    pieces.push(Some(rest));
    super::team::for_each_item(&mut pieces, |_, p| {
        if let Some(p) = p.take() {
            body(p)
        }
    });
}

/// Elements per task of [`par_max_zip`].
const SLICE_CHUNK: usize = 8192;

/// The largest `f(&a[k], &b[k])` over k (0 for empty slices), on all cores when the
/// slices are long. The maximum does not depend on the chunking.
pub fn par_max_zip<A: Sync, B: Sync>(
    a: &[A],
    b: &[B],
    f: impl Fn(&A, &B) -> f64 + Send + Sync,
) -> f64 {
    let n = a.len().min(b.len());
    let max = |x: &[A], y: &[B]| {
        x.iter()
            .zip(y)
            .map(|(x, y)| f(x, y))
            .fold(0.0_f64, f64::max)
    };
    if n < 2 * SLICE_CHUNK {
        return max(&a[..n], &b[..n]);
    }
    let mut out = vec![0.0_f64; n.div_ceil(SLICE_CHUNK)];
    super::team::for_each_item(&mut out, |c, m| {
        let (lo, hi) = (c * SLICE_CHUNK, ((c + 1) * SLICE_CHUNK).min(n));
        *m = max(&a[lo..hi], &b[lo..hi]);
    });
    out.into_iter().fold(0.0_f64, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pieces cut at listed rows hold about [`LISTED_PIECE`] listed rows each, cover the
    /// table once, and a list gathered at one end of the table is still spread.
    #[test]
    fn listed_pieces_share_the_list() {
        let rows = 100_000;
        let listed: Vec<u32> = (0..1000).map(|k| 3 * k + 1).collect();
        let seen = std::sync::Mutex::new(Vec::new());
        for_each_listed_piece(Rows(0..rows), Some(&listed), |piece| {
            let mine = piece.within(&listed).len();
            seen.lock().unwrap().push((piece.0.clone(), mine));
        });
        let mut seen = seen.into_inner().unwrap();
        seen.sort_by_key(|(r, _)| r.start);
        let per = LISTED_PIECE.min(parallel_min().div_ceil(2).max(1));
        assert_eq!(seen.len(), listed.len().div_ceil(per));
        assert!(seen.iter().all(|(_, m)| (1..=per).contains(m)), "{seen:?}");
        assert_eq!(seen.iter().map(|(_, m)| m).sum::<usize>(), listed.len());
        assert_eq!(seen[0].0.start, 0);
        assert_eq!(seen.last().unwrap().0.end, rows);
        assert!(seen.windows(2).all(|w| w[0].0.end == w[1].0.start));
    }

    /// Row ranges cut like columns, and each piece finds exactly its members of a sorted
    /// row list.
    #[test]
    fn rows_split_like_columns_and_pick_their_members() {
        let (a, b) = Rows(10..30).split_at(7);
        assert_eq!((a.clone(), b.clone()), (Rows(10..17), Rows(17..30)));
        let (col_a, col_b) = [0u8; 20][..].split_at(7);
        assert_eq!((a.rows(), b.rows()), (col_a.len(), col_b.len()));
        let sorted = [3, 10, 16, 17, 29, 30, 31];
        assert_eq!(a.within(&sorted), &[10, 16]);
        assert_eq!(b.within(&sorted), &[17, 29]);
        assert!(Rows(0..3).within(&sorted).is_empty());
        let seen = |only: Option<&[u32]>| {
            let mut v = Vec::new();
            b.visit(only, |i| v.push(i));
            v
        };
        assert_eq!(seen(Some(&sorted)), [0, 12]);
        assert_eq!(seen(None), (0..13).collect::<Vec<_>>());
    }
}
