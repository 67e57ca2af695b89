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
pub fn layout(cells: &[Cell], legend: &[String], exposure: f32) -> RgbImage {
    layout_grid(&[cells.to_vec()], legend, exposure)
}

/// Lays rows of cells out as a grid: every cell as wide as the widest image or label (labels
/// kept a gap apart), every row as tall as its tallest image and its labels; under them the
/// `legend`, lines that say what the labels' numbers are (in the label font, at half size when
/// a line is wider than the grid).
pub fn layout_grid(rows: &[Vec<Cell>], legend: &[String], exposure: f32) -> RgbImage {
    let scale = 2;
    let pad = 8;
    let line = 9 * scale;
    let all = || rows.iter().flatten();
    let widest_label = all().flat_map(|c| c.label.iter().map(|l| text_width(l, scale))).max().unwrap_or(0);
    // Labels as wide as their cell would touch their neighbours': one character's gap.
    let cell_w = all().map(|c| c.image.width).max().unwrap_or(0).max(widest_label + 6 * scale);
    let row_h = |row: &[Cell]| {
        let image = row.iter().map(|c| c.image.height).max().unwrap_or(0);
        let lines = row.iter().map(|c| c.label.len()).max().unwrap_or(0);
        (image, pad + image + pad + lines * line)
    };
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let width = columns * (cell_w + pad) + pad;
    let legend_scale = if legend.iter().all(|l| text_width(l, scale) + 2 * pad <= width) { scale } else { 1 };
    let legend_h = if legend.is_empty() { 0 } else { pad + legend.len() * 9 * legend_scale };
    let grid_h = rows.iter().map(|r| row_h(r).1).sum::<usize>() + pad;
    let height = grid_h + legend_h;
    let width = width.max(legend.iter().map(|l| text_width(l, legend_scale) + 2 * pad).max().unwrap_or(0));
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
    for (k, l) in legend.iter().enumerate() {
        draw_text(&mut out, pad, grid_h + pad + k * 9 * legend_scale, l, legend_scale, white);
    }
    out
}
