//! Several renders side by side with a label under each, as the papers' figures are laid out.

use super::font::{draw_text, text_width};
use crate::io::RgbImage;

/// One cell of a panel: an image (linear) and its label lines.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The image, linear RGB.
    pub image: RgbImage,
    /// Label lines drawn under it.
    pub label: Vec<String>,
}

/// Lays `cells` out in one row (tone mapping is applied later; labels are drawn in white at
/// radiance 1/exposure-scale so they stay white after tone mapping with `exposure` stops).
pub fn layout(cells: &[Cell], exposure: f32) -> RgbImage {
    layout_grid(&[cells.to_vec()], exposure)
}

/// Lays rows of cells out as a grid: every cell as wide as the widest image or label, every row
/// as tall as its tallest image and its labels.
pub fn layout_grid(rows: &[Vec<Cell>], exposure: f32) -> RgbImage {
    let scale = 2;
    let pad = 8;
    let line = 9 * scale;
    let all = || rows.iter().flatten();
    let cell_w = all()
        .map(|c| c.image.width.max(c.label.iter().map(|l| text_width(l, scale)).max().unwrap_or(0)))
        .max()
        .unwrap_or(0);
    let row_h = |row: &[Cell]| {
        let image = row.iter().map(|c| c.image.height).max().unwrap_or(0);
        let lines = row.iter().map(|c| c.label.len()).max().unwrap_or(0);
        (image, pad + image + pad + lines * line)
    };
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let width = columns * (cell_w + pad) + pad;
    let height = rows.iter().map(|r| row_h(r).1).sum::<usize>() + pad;
    let mut out = RgbImage::new(width.max(1), height.max(1));
    let white = [2f32.powf(-exposure); 3];
    let mut y0 = 0;
    for row in rows {
        let (image_h, total_h) = row_h(row);
        for (i, c) in row.iter().enumerate() {
            let x0 = pad + i * (cell_w + pad) + (cell_w - c.image.width) / 2;
            for y in 0..c.image.height {
                for x in 0..c.image.width {
                    out.set(x0 + x, y0 + pad + y, c.image.get(x, y));
                }
            }
            for (k, l) in c.label.iter().enumerate() {
                let tx = pad + i * (cell_w + pad) + (cell_w - text_width(l, scale).min(cell_w)) / 2;
                draw_text(&mut out, tx, y0 + 2 * pad + image_h + k * line, l, scale, white);
            }
        }
        y0 += total_h;
    }
    out
}
