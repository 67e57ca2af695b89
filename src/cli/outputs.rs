//! The outputs of one command line, written all or none (`io::OutputSet`): documents as JSON,
//! images by their file's extension (EXR on standard output), GPU textures in their container
//! (`io::texture`), summaries on stdout.

use crate::io::gpu_format::{TexelFormat, Texture};
use crate::io::texture::Container;
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

    /// Stages a GPU texture packed in `format`, in `container` (KTX2 or DDS).
    pub fn texture(
        &mut self,
        output: &Output,
        container: Container,
        texture: &Texture,
        format: TexelFormat,
    ) -> Result<()> {
        let bytes = container.encode(texture, format).with_context(|| format!("cannot encode {}", output.display()))?;
        self.bytes(output, bytes)
    }

    /// Puts every staged output in place.
    pub fn commit(self) -> Result<()> {
        Ok(self.set.commit()?)
    }
}

/// What an output will hold, which decides the file names that fit it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Holds {
    /// A document, a table or a plot: any name.
    Text,
    /// An image, in the format its extension names: `.exr`, `.pfm` or `.png` (tone-mapped);
    /// EXR on standard output.
    Image,
    /// A tone-mapped picture: `.png`.
    Png,
    /// Linear data in layers: `.exr`.
    Exr,
    /// A binary glTF: `.glb`.
    Glb,
    /// A transfer job's part (`transfer --job`): `.part`.
    Part,
}

impl Holds {
    /// Whether `output` can hold this.
    fn check(self, output: &Output) -> Result<()> {
        let Output::File(path) = output else { return Ok(()) };
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let fits = match self {
            Holds::Text => true,
            Holds::Image => matches!(ext.as_deref(), Some("exr" | "pfm" | "png")),
            Holds::Png => ext.as_deref() == Some("png"),
            Holds::Exr => ext.as_deref() == Some("exr"),
            Holds::Glb => ext.as_deref() == Some("glb"),
            Holds::Part => ext.as_deref() == Some("part"),
        };
        if !fits {
            let expected = match self {
                Holds::Text => "",
                Holds::Image => ".exr, .pfm or .png",
                Holds::Png => ".png",
                Holds::Exr => ".exr",
                Holds::Glb => ".glb",
                Holds::Part => ".part",
            };
            anyhow::bail!("{}: unknown output format: the name must end in {expected}", path.display());
        }
        Ok(())
    }
}

/// Checks every output before the work starts, so that a run never computes for minutes and
/// then fails to write: its name fits what it will hold, its directory exists (a missing one is
/// refused, never created: `docs/cli.md`) and takes files, and standard output is claimed at
/// most once.
pub fn check_outputs<'a>(outputs: impl IntoIterator<Item = (&'a Output, Holds)>) -> Result<()> {
    let mut stdout = 0;
    for (output, holds) in outputs {
        if *output == Output::Stdout {
            stdout += 1;
        }
        holds.check(output)?;
        output.check_writable()?;
    }
    if stdout > 1 {
        anyhow::bail!("only one output can go to standard output (-)");
    }
    Ok(())
}

/// Checks a directory that a run creates for its outputs (`ibl -o DIR`, `--views-dir DIR`):
/// its parent must exist, as for every output file (one rule: a run creates the directory it
/// is given, never the path to it), and take files.
pub fn check_output_dir(dir: &Path) -> Result<()> {
    if dir.is_dir() {
        return Output::File(dir.join(".prtkit-probe")).check_writable().map_err(Into::into);
    }
    if dir.exists() {
        anyhow::bail!("{}: exists and is not a directory", dir.display());
    }
    Output::File(dir.to_path_buf()).check_writable()?;
    Ok(())
}
