//! Compressed sparse rows ([`Csr`]): items grouped by row in one array, row
//! `r` at `items[offsets[r]..offsets[r + 1]]`, built by a counting sort that
//! keeps, within a row, the order in which the items were placed. Rebuilding
//! reuses every buffer.
//!
//! Built either in one call ([`Csr::rebuild`], from a function giving the
//! same `(row, item)` sequence twice) or in its two passes when the caller
//! walks its own structures: [`Csr::begin`], [`Csr::count`] for every item,
//! [`Csr::allocate`], then [`Csr::place`] for the same items in the order
//! they should keep.
//!
//! [`CsrView`] is the borrowed form (a `Csr`'s [`view`](Csr::view), or
//! offsets and items held elsewhere): what readers of rows take.

use std::ops::Range;

/// Compressed rows held elsewhere, borrowed: row `r` is
/// `items[offsets[r]..offsets[r + 1]]`.
#[derive(Debug, PartialEq, Eq)]
pub struct CsrView<'a, T> {
    offsets: &'a [u32],
    items: &'a [T],
}

impl<T> Clone for CsrView<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for CsrView<'_, T> {}

impl<'a, T> CsrView<'a, T> {
    /// Rows over `items` starting at `offsets` (one more offset than rows,
    /// the last `items.len()`; or no offsets at all for no rows).
    pub fn new(offsets: &'a [u32], items: &'a [T]) -> Self {
        debug_assert!(offsets.last().map_or(items.is_empty(), |&end| end as usize == items.len()));
        Self { offsets, items }
    }

    /// Row `r`'s items (`r` must be below [`rows`](Self::rows)).
    #[inline]
    pub fn row(&self, r: usize) -> &'a [T] {
        &self.items[self.span(r)]
    }

    /// Where row `r`'s items lie in [`items`](Self::items) (`r` must be
    /// below [`rows`](Self::rows)).
    #[inline]
    pub fn span(&self, r: usize) -> Range<usize> {
        self.offsets[r] as usize..self.offsets[r + 1] as usize
    }

    /// Number of rows.
    #[inline]
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Every item, row after row.
    #[inline]
    pub fn items(&self) -> &'a [T] {
        self.items
    }

    /// The row offsets.
    #[inline]
    pub fn offsets(&self) -> &'a [u32] {
        self.offsets
    }

    /// Number of items in all rows.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no row holds an item.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

impl<'a, T> From<(&'a [u32], &'a [T])> for CsrView<'a, T> {
    /// From a pair `(offsets, items)`.
    fn from((offsets, items): (&'a [u32], &'a [T])) -> Self {
        Self::new(offsets, items)
    }
}

/// Items grouped by row (module notes).
#[derive(Debug, Default)]
pub struct Csr<T> {
    offsets: Vec<u32>,
    items: Vec<T>,
    /// Where the next placed item of each row goes (during a build).
    cursor: Vec<u32>,
}

impl<T: Copy + Default> Csr<T> {
    /// No rows.
    pub fn new() -> Self {
        Self { offsets: Vec::new(), items: Vec::new(), cursor: Vec::new() }
    }

    /// Rebuilds with `rows` rows from the `(row, item)` pairs `entries`
    /// yields (called twice; it must yield the same sequence both times).
    /// Within a row the items keep the order of the sequence.
    pub fn rebuild<I: IntoIterator<Item = (usize, T)>>(&mut self, rows: usize, entries: impl Fn() -> I) {
        self.begin(rows);
        entries().into_iter().for_each(|(r, _)| self.count(r));
        self.allocate();
        entries().into_iter().for_each(|(r, item)| self.place(r, item));
    }

    /// Room for builds of up to `rows` rows without allocating.
    pub fn reserve_rows(&mut self, rows: usize) {
        self.offsets.reserve((rows + 1).saturating_sub(self.offsets.len()));
        self.cursor.reserve(rows.saturating_sub(self.cursor.len()));
    }

    /// Room for builds (or copies) of up to `items` items without
    /// allocating.
    pub fn reserve_items(&mut self, items: usize) {
        self.items.reserve(items.saturating_sub(self.items.len()));
    }

    /// The items the rows have room for without allocating.
    pub fn items_capacity(&self) -> usize {
        self.items.capacity()
    }

    /// First pass of a build: `rows` empty rows, every count 0.
    pub fn begin(&mut self, rows: usize) {
        self.offsets.clear();
        self.offsets.resize(rows + 1, 0);
    }

    /// First pass: one more item for row `r`.
    #[inline]
    pub fn count(&mut self, r: usize) {
        self.offsets[r + 1] += 1;
    }

    /// First pass: `n` more items for row `r`.
    #[inline]
    pub fn count_many(&mut self, r: usize, n: usize) {
        self.offsets[r + 1] += n as u32;
    }

    /// Between the passes: turns the counts into offsets and sizes the items.
    pub fn allocate(&mut self) {
        let rows = self.rows();
        for r in 0..rows {
            self.offsets[r + 1] += self.offsets[r];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.offsets[..rows]);
        self.items.clear();
        self.items.resize(self.offsets[rows] as usize, T::default());
    }

    /// Second pass: the next item of row `r` (as many per row as counted).
    #[inline]
    pub fn place(&mut self, r: usize, item: T) {
        let slot = &mut self.cursor[r];
        self.items[*slot as usize] = item;
        *slot += 1;
    }

    /// Second pass: the next items of row `r` (as many per row as counted).
    #[inline]
    pub fn place_all(&mut self, r: usize, items: &[T]) {
        let slot = &mut self.cursor[r];
        let at = *slot as usize;
        self.items[at..at + items.len()].copy_from_slice(items);
        *slot += items.len() as u32;
    }

    /// Number of rows.
    #[inline]
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Row `r`'s items (none for a row past the end).
    #[inline]
    pub fn row(&self, r: usize) -> &[T] {
        &self.items[self.span(r)]
    }

    /// Row `r`'s items, to reorder them in place.
    #[inline]
    pub fn row_mut(&mut self, r: usize) -> &mut [T] {
        let span = self.span(r);
        &mut self.items[span]
    }

    /// Where row `r`'s items lie in [`items`](Self::items) (empty past the end).
    #[inline]
    pub fn span(&self, r: usize) -> Range<usize> {
        match (self.offsets.get(r), self.offsets.get(r + 1)) {
            (Some(&a), Some(&b)) => a as usize..b as usize,
            _ => 0..0,
        }
    }

    /// Every item, row after row.
    #[inline]
    pub fn items(&self) -> &[T] {
        &self.items
    }

    /// The row offsets (`rows() + 1` of them, or none before a build).
    #[inline]
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// Number of items in all rows.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no row holds an item.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The rows, borrowed.
    #[inline]
    pub fn view(&self) -> CsrView<'_, T> {
        CsrView::new(&self.offsets, &self.items)
    }

    /// Becomes a copy of `rows` (reusing the buffers).
    pub fn copy_from(&mut self, rows: CsrView<'_, T>) {
        self.offsets.clear();
        self.offsets.extend_from_slice(rows.offsets());
        self.items.clear();
        self.items.extend_from_slice(rows.items());
    }
}

crate::memory::clone_by_fields!(Csr<T> { offsets, items, cursor });

impl<T: Copy> crate::memory::HeapSize for Csr<T> {
    fn heap_bytes(&self) -> usize {
        let Self { offsets, items, cursor } = self;
        offsets.heap_bytes() + items.heap_bytes() + cursor.heap_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_keep_the_order_items_were_placed_in() {
        let mut csr = Csr::new();
        let entries = [(2, 'a'), (0, 'b'), (2, 'c'), (3, 'd'), (0, 'e')];
        csr.rebuild(4, || entries);
        assert_eq!(csr.rows(), 4);
        assert_eq!(csr.row(0), &['b', 'e']);
        assert!(csr.row(1).is_empty());
        assert_eq!(csr.row(2), &['a', 'c']);
        assert_eq!(csr.row(3), &['d']);
        assert!(csr.row(9).is_empty());
        assert_eq!(csr.offsets(), &[0, 2, 2, 4, 5]);
        assert_eq!(csr.len(), 5);
        // A rebuild forgets the old rows and reuses the buffers.
        csr.begin(2);
        csr.count(1);
        csr.allocate();
        csr.place(1, 'z');
        assert_eq!((csr.rows(), csr.row(0).len(), csr.row(1)), (2, 0, &['z'][..]));
        csr.row_mut(1)[0] = 'y';
        assert_eq!(csr.items(), &['y']);
        csr.begin(3);
        csr.count_many(2, 2);
        csr.count(0);
        csr.allocate();
        csr.place_all(2, &['p', 'q']);
        csr.place(0, 'o');
        assert_eq!((csr.offsets(), csr.items()), (&[0, 1, 1, 3][..], &['o', 'p', 'q'][..]));
        csr.begin(1);
        csr.count(0);
        csr.allocate();
        csr.place(0, 'y');
        assert_eq!(csr.items(), &['y']);
        assert!(Csr::<u32>::new().row(0).is_empty() && Csr::<u32>::new().rows() == 0);
    }

    #[test]
    fn a_view_reads_the_rows_it_borrows() {
        let mut csr = Csr::new();
        csr.rebuild(3, || [(2, 7u32), (0, 5), (2, 9)]);
        let view = csr.view();
        assert_eq!(
            (view.rows(), view.len(), view.row(0), view.row(1), view.row(2)),
            (3, 3, &[5][..], &[][..], &[7, 9][..])
        );
        assert_eq!(view.span(2), 1..3);
        let mut copy = Csr::new();
        copy.copy_from(view);
        assert_eq!((copy.offsets(), copy.items()), (csr.offsets(), csr.items()));
        let empty = CsrView::<u32>::new(&[], &[]);
        assert_eq!((empty.rows(), empty.is_empty()), (0, true));
        assert_eq!(CsrView::from((&[0, 1][..], &[4u32][..])).row(0), &[4]);
    }
}
