//! Stacks panel PNGs (as `render --panel` writes them, one row each) into one picture, top to
//! bottom, each centred on a black background: how scripts/demo.sh assembles
//! docs/transfer-relit.png from one `render` panel per lighting.
//!
//! `cargo run --release --example stack_panels -- OUT.png ROW.png…`

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((out, rows)) = args.split_first().filter(|(_, rows)| !rows.is_empty()) else {
        eprintln!("usage: stack_panels OUT.png ROW.png…");
        std::process::exit(2);
    };
    let rows: Vec<image::RgbImage> =
        rows.iter().map(|p| image::open(p).unwrap_or_else(|e| panic!("{p}: {e}")).to_rgb8()).collect();
    let width = rows.iter().map(|r| r.width()).max().unwrap_or(0);
    let height = rows.iter().map(|r| r.height()).sum();
    let mut stacked = image::RgbImage::new(width, height);
    let mut y = 0;
    for r in &rows {
        image::imageops::replace(&mut stacked, r, ((width - r.width()) / 2) as i64, y as i64);
        y += r.height();
    }
    stacked.save(out).unwrap_or_else(|e| panic!("{out}: {e}"));
}
