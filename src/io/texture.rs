//! Texture files: the container a GPU texture is written in (KTX 2.0 or DDS) and the one call
//! that encodes a [`Texture`] into it, so that every writer of textures — the `ibl` binary, its
//! example, the tests — produces the same bytes from the same values.

use super::gpu_format::{TexelFormat, Texture, TextureError};
use super::{dds, ktx2};

/// A texture file's container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// KTX 2.0 ([`ktx2`]).
    Ktx2,
    /// DDS with the DX10 header ([`dds`]).
    Dds,
}

impl Container {
    /// The container's name, which is also its files' extension: `ktx2` or `dds`.
    pub fn name(self) -> &'static str {
        match self {
            Container::Ktx2 => "ktx2",
            Container::Dds => "dds",
        }
    }

    /// The file's bytes: `texture` packed in `format`, in this container.
    pub fn encode(self, texture: &Texture, format: TexelFormat) -> Result<Vec<u8>, TextureError> {
        match self {
            Container::Ktx2 => ktx2::encode(texture, format),
            Container::Dds => dds::encode(texture, format),
        }
    }
}
