//! Reducing RGB BRDF values to the one scalar the SVD factors.

/// Which scalar of an RGB BRDF to factor. Analytic models are grey, so every choice agrees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Channel {
    /// Rec. 709 luminance 0.2126 R + 0.7152 G + 0.0722 B.
    Luminance,
    /// (R + G + B)/3, as in Mahajan et al. 2008, Fig. 7 ("averaged across the RGB colors").
    Mean,
    /// Red only.
    R,
    /// Green only.
    G,
    /// Blue only.
    B,
}

impl Channel {
    /// The weights applied to (R, G, B).
    pub fn weights(self) -> [f64; 3] {
        match self {
            Channel::Luminance => [0.2126, 0.7152, 0.0722],
            Channel::Mean => [1.0 / 3.0; 3],
            Channel::R => [1.0, 0.0, 0.0],
            Channel::G => [0.0, 1.0, 0.0],
            Channel::B => [0.0, 0.0, 1.0],
        }
    }

    /// The scalar of an RGB value.
    #[inline]
    pub fn apply(self, rgb: [f64; 3]) -> f64 {
        let w = self.weights();
        w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2]
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Luminance => "luminance",
            Channel::Mean => "mean",
            Channel::R => "r",
            Channel::G => "g",
            Channel::B => "b",
        }
    }
}

impl std::fmt::Display for Channel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
