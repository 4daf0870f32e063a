//! How far the moving surfaces of a velocity buffer reach, on a grid of small cells: what lets
//! the reconstruction filter (`reconstruct`) skip the taps that cannot weigh anything.
//!
//! A tap of the gather at distance `d` from its pixel has a zero foreground weight when
//! `d >= r_Y + 1` (`r_Y` the half speed of the tapped pixel) and a zero background weight when
//! `d >= r_X + 1` (`r_X` the pixel's own): such a tap only counts in the number of taps. The
//! grid keeps, per `CELL x CELL` cell, the largest half speed of its pixels (`cell`) and the
//! largest of those over every cell a tap of the cell's pixels can land on (`reach`): taps lie
//! within `|n_x| + 1`, `|n_y| + 1` pixels of their pixel along each axis (`n` the neighbour max,
//! whose components are bounded by `nx`, `ny` over the image).
use rayon::prelude::*;

/// Side of a cell in pixels.
pub(crate) const CELL: usize = 16;

/// The cell grid of an image (module docs).
pub(crate) struct Reach {
    /// Cells along a row.
    pub cw: usize,
    /// Largest half speed in each cell (row-major, `cw` a row).
    pub cell: Vec<f32>,
    /// Largest `cell` value over the cells a tap of each cell's pixels can land on.
    pub reach: Vec<f32>,
}

impl Reach {
    /// The grid of `speed` (the half speed of each pixel, >= 0) over a `w` x `h` image whose
    /// taps reach at most `nx`, `ny` pixels (plus one) from their pixel along x and y.
    #[cfg(test)]
    pub fn new(speed: &[f32], w: usize, h: usize, nx: f32, ny: f32) -> Reach {
        let (cw, ch) = (w.div_ceil(CELL), h.div_ceil(CELL));
        let cell: Vec<f32> = (0..cw * ch)
            .into_par_iter()
            .map(|c| {
                let (cx, cy) = (c % cw, c / cw);
                let (x0, x1) = (cx * CELL, ((cx + 1) * CELL).min(w));
                (cy * CELL..((cy + 1) * CELL).min(h)).fold(0.0f32, |m, y| {
                    speed[y * w + x0..y * w + x1]
                        .iter()
                        .fold(m, |m, s| m.max(*s))
                })
            })
            .collect();
        Reach::from_cells(cell, cw, ch, nx, ny)
    }

    /// [`Reach::new`] from the largest half speed of each cell's part of each row
    /// (`cell_rows`, `w.div_ceil(CELL)` a row, `h` rows): the same grid.
    pub fn from_rows(cell_rows: &[f32], w: usize, h: usize, nx: f32, ny: f32) -> Reach {
        let (cw, ch) = (w.div_ceil(CELL), h.div_ceil(CELL));
        let cell: Vec<f32> = (0..cw * ch)
            .into_par_iter()
            .map(|c| {
                let (cx, cy) = (c % cw, c / cw);
                (cy * CELL..((cy + 1) * CELL).min(h))
                    .fold(0.0f32, |m, y| m.max(cell_rows[y * cw + cx]))
            })
            .collect();
        Reach::from_cells(cell, cw, ch, nx, ny)
    }

    /// The grid of the cells' largest half speeds `cell` (`cw` x `ch`).
    fn from_cells(cell: Vec<f32>, cw: usize, ch: usize, nx: f32, ny: f32) -> Reach {
        // cells within ceil((n + 1) / CELL) of a cell hold every pixel its pixels' taps reach
        let radius = |n: f32, cells: usize| (((n + 1.0) / CELL as f32).ceil() as usize).min(cells);
        let (rx, ry) = (radius(nx, cw), radius(ny, ch));
        let reach = window_max(&cell, cw, ch, rx, ry);
        Reach { cw, cell, reach }
    }

    /// The cell of pixel `(x, y)`.
    #[inline(always)]
    pub fn index(&self, x: usize, y: usize) -> usize {
        (y / CELL) * self.cw + x / CELL
    }
}

/// The maximum of the `cw` x `ch` grid `a` over windows of `rx` cells either side along x and
/// `ry` cells either side along y (cells past the edges count as 0; every value is >= 0).
fn window_max(a: &[f32], cw: usize, ch: usize, rx: usize, ry: usize) -> Vec<f32> {
    let span = |k: usize, r: usize, n: usize| k.saturating_sub(r)..=(k + r).min(n - 1);
    let rows: Vec<f32> = (0..cw * ch)
        .into_par_iter()
        .map(|c| {
            let (cx, cy) = (c % cw, c / cw);
            span(cx, rx, cw).fold(0.0f32, |m, x| m.max(a[cy * cw + x]))
        })
        .collect();
    (0..cw * ch)
        .into_par_iter()
        .map(|c| {
            let (cx, cy) = (c % cw, c / cw);
            span(cy, ry, ch).fold(0.0f32, |m, y| m.max(rows[y * cw + cx]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reach_covers_the_taps_of_every_cell() {
        // one moving pixel at (40, 20) of half speed 3 in a 100 x 50 image
        let (w, h) = (100, 50);
        let mut speed = vec![0.0f32; w * h];
        speed[20 * w + 40] = 3.0;
        let r = Reach::new(&speed, w, h, 20.0, 0.0);
        assert_eq!(r.cell[r.index(40, 20)], 3.0);
        assert_eq!(r.cell.iter().filter(|&&v| v > 0.0).count(), 1);
        // taps reach 21 pixels along x (2 cells either side) and 1 along y (1 cell either side):
        // every pixel a tap from which can land on (40, 20) sees its speed
        for x in 0..w {
            for y in 0..h {
                let near = (x as i64 - 40).abs() <= 21 && (y as i64 - 20).abs() <= 1;
                if near {
                    assert_eq!(r.reach[r.index(x, y)], 3.0, "({x}, {y})");
                }
            }
        }
        // and the cells 3 or more cells across, or 2 or more down, do not
        assert_eq!(r.reach[r.index(99, 20)], 0.0);
        assert_eq!(r.reach[r.index(40, 49)], 0.0);
        assert_eq!(r.reach[r.index(0, 16)], 3.0);
        // the grid from the rows' maxima is the same
        let cw = w.div_ceil(CELL);
        let rows: Vec<f32> = (0..h * cw)
            .map(|k| {
                let (y, cx) = (k / cw, k % cw);
                speed[y * w + cx * CELL..y * w + ((cx + 1) * CELL).min(w)]
                    .iter()
                    .fold(0.0f32, |m, s| m.max(*s))
            })
            .collect();
        let q = Reach::from_rows(&rows, w, h, 20.0, 0.0);
        assert_eq!((q.cw, &q.cell, &q.reach), (r.cw, &r.cell, &r.reach));
    }
}
