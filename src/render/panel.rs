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
    let scale = 2;
    let pad = 8;
    let line = 9 * scale;
    let lines = cells.iter().map(|c| c.label.len()).max().unwrap_or(0);
    let cell_w = cells
        .iter()
        .map(|c| c.image.width.max(c.label.iter().map(|l| text_width(l, scale)).max().unwrap_or(0)))
        .max()
        .unwrap_or(0);
    let cell_h = cells.iter().map(|c| c.image.height).max().unwrap_or(0);
    let width = cells.len() * (cell_w + pad) + pad;
    let height = pad + cell_h + pad + lines * line + pad;
    let mut out = RgbImage::new(width.max(1), height.max(1));
    let white = [2f32.powf(-exposure); 3];
    for (i, c) in cells.iter().enumerate() {
        let x0 = pad + i * (cell_w + pad) + (cell_w - c.image.width) / 2;
        for y in 0..c.image.height {
            for x in 0..c.image.width {
                out.set(x0 + x, pad + y, c.image.get(x, y));
            }
        }
        for (k, l) in c.label.iter().enumerate() {
            let tx = pad + i * (cell_w + pad) + (cell_w - text_width(l, scale).min(cell_w)) / 2;
            draw_text(&mut out, tx, 2 * pad + cell_h + k * line, l, scale, white);
        }
    }
    out
}
