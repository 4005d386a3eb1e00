//! The item lists of a uniform grid's cells, shared by the grid indexes
//! ([`DiskGrid`](super::DiskGrid), [`BoxIndex`](super::BoxIndex)).

/// The lists of which items cover each cell of a `columns` x `rows` grid, given each
/// item's cell range `[c0, r0, c1, r1]` (inclusive; `None`: the item is in no cell), as
/// `(start, items)`: the items of cell `k = r * columns + c` are
/// `items[start[k]..start[k + 1]]`, in item order.
pub(super) fn cell_lists(
    columns: usize,
    rows: usize,
    ranges: &[Option<[usize; 4]>],
) -> (Vec<u32>, Vec<u32>) {
    let cells = || {
        ranges
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.map(|r| (i, r)))
            .flat_map(move |(i, [c0, r0, c1, r1])| {
                (r0..=r1).flat_map(move |r| (c0..=c1).map(move |c| (i, r * columns + c)))
            })
    };
    let mut counts = vec![0u32; columns * rows];
    for (_, k) in cells() {
        counts[k] += 1;
    }
    let mut start = Vec::with_capacity(counts.len() + 1);
    let mut total = 0u32;
    for n in &counts {
        start.push(total);
        total += n;
    }
    start.push(total);
    let mut fill = start.clone();
    let mut items = vec![0u32; total as usize];
    for (i, k) in cells() {
        items[fill[k] as usize] = i as u32;
        fill[k] += 1;
    }
    (start, items)
}
