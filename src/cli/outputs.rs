//! The outputs of one command line, written all or none (`io::OutputSet`): documents as JSON,
//! images by their file's extension (EXR on standard output), summaries on stdout.

use crate::io::{self, document::to_json_pretty, Output, OutputSet, RgbImage};
use anyhow::{Context as _, Result};
use serde::Serialize;
use std::path::Path;

/// Outputs staged for one all-or-nothing commit.
#[derive(Default)]
pub struct Outputs {
    set: OutputSet,
}

impl Outputs {
    /// Nothing staged yet.
    pub fn new() -> Self {
        Outputs::default()
    }

    /// Creates a directory for outputs; removed again if the run fails before the commit.
    pub fn create_dir(&mut self, dir: &Path) -> Result<()> {
        Ok(self.set.create_dir(dir)?)
    }

    /// Stages raw bytes.
    pub fn bytes(&mut self, output: &Output, bytes: Vec<u8>) -> Result<()> {
        Ok(self.set.add(output, bytes)?)
    }

    /// Stages a JSON document or summary (pretty, trailing newline).
    pub fn json<T: Serialize + ?Sized>(&mut self, output: &Output, value: &T) -> Result<()> {
        self.bytes(output, to_json_pretty(value).into_bytes())
    }

    /// Stages an image: `.exr`, `.pfm` or `.png` (tone-mapped with `exposure` stops) by the
    /// file's extension; standard output gets EXR.
    pub fn image(&mut self, output: &Output, image: &RgbImage, exposure: f32) -> Result<()> {
        let bytes = match output {
            Output::Stdout => io::image::encode_image(Path::new("-.exr"), image, exposure),
            Output::File(path) => io::image::encode_image(path, image, exposure),
        }
        .with_context(|| format!("cannot encode {}", output.display()))?;
        self.bytes(output, bytes)
    }

    /// Stages named RGB layers as one EXR.
    pub fn layers(&mut self, output: &Output, layers: &[(String, RgbImage)]) -> Result<()> {
        let refs: Vec<(&str, &RgbImage)> = layers.iter().map(|(n, i)| (n.as_str(), i)).collect();
        let bytes =
            io::exr::encode_layers(&refs).map_err(|e| anyhow::anyhow!("cannot encode {}: {e}", output.display()))?;
        self.bytes(output, bytes)
    }

    /// Puts every staged output in place.
    pub fn commit(self) -> Result<()> {
        Ok(self.set.commit()?)
    }
}

/// Checks, before long work, that every output can be written (its directory exists and is
/// writable) and that standard output is claimed at most once.
pub fn check_writable<'a>(outputs: impl IntoIterator<Item = &'a Output>) -> Result<()> {
    let mut stdout = 0;
    for output in outputs {
        if *output == Output::Stdout {
            stdout += 1;
        }
        output.check_writable()?;
    }
    if stdout > 1 {
        anyhow::bail!("only one output can go to standard output (-)");
    }
    Ok(())
}
