//! The model's input features (hdr, alb, nrm, and for models trained with them emi, ema) and the files
//! they are read from, found next to the noisy image by the OIDN naming (`<img>.hdr.exr` →
//! `<img>.alb.exr`, output `<img>.dn.exr`).

use luxest_io::naming::{self, Kind};
use std::path::{Path, PathBuf};

/// One input feature of a model, in the order the model's channels expect them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    Hdr,
    Alb,
    Nrm,
    /// The emitted radiance seen directly (aov-write's `emi`, the image's own samples): a model
    /// that takes it denoises hdr − emi and adds it back.
    Emi,
    /// The same over at least aov-write's `--min-samples` (`ema`, antialiased): a model that
    /// takes it adds it back in place of `emi` (which it still subtracts).
    Ema,
}

impl Feature {
    /// Every feature, in channel order.
    pub const ALL: [Feature; 5] = [
        Feature::Hdr,
        Feature::Alb,
        Feature::Nrm,
        Feature::Emi,
        Feature::Ema,
    ];
    /// The image kind of the feature's files (`<img>_<spp>spp.<tag>.exr`).
    pub fn kind(self) -> Kind {
        match self {
            Feature::Hdr => Kind::Hdr,
            Feature::Alb => Kind::Alb,
            Feature::Nrm => Kind::Nrm,
            Feature::Emi => Kind::Emission,
            Feature::Ema => Kind::EmissionAntialiased,
        }
    }
    /// Whether the feature is radiance (scaled with hdr near the f32 limit), not a property of
    /// the surface.
    pub fn is_radiance(self) -> bool {
        matches!(self, Feature::Hdr | Feature::Emi | Feature::Ema)
    }
    /// The feature's name in file names and in the model's `luxest.channels` metadata.
    pub fn name(self) -> &'static str {
        self.kind().tag()
    }
    pub(crate) fn parse(s: &str) -> Option<Feature> {
        Feature::ALL.into_iter().find(|f| f.name() == s.trim())
    }
}

pub(crate) fn names(features: &[Feature]) -> String {
    features
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The feature files of a noisy image `<stem>.hdr.exr`: `<stem>.<feature>.exr`.
pub fn feature_path(hdr: &Path, feature: Feature) -> Option<PathBuf> {
    naming::split_kind(hdr.file_name()?.to_str()?)
        .filter(|(_, kind)| *kind == Kind::Hdr)
        .and(naming::sibling(hdr, feature.kind()))
}

/// The output of a noisy image `<stem>.hdr.exr`: `<stem>.dn.exr`.
pub fn output_path(hdr: &Path) -> Option<PathBuf> {
    naming::split_kind(hdr.file_name()?.to_str()?)
        .filter(|(_, kind)| *kind == Kind::Hdr)
        .and(naming::sibling(hdr, Kind::Denoised))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_and_output_names_follow_the_oidn_layout() {
        let p = Path::new("data/x/gen0001_000004spp.hdr.exr");
        assert_eq!(
            feature_path(p, Feature::Nrm).unwrap(),
            Path::new("data/x/gen0001_000004spp.nrm.exr")
        );
        assert_eq!(
            output_path(p).unwrap(),
            Path::new("data/x/gen0001_000004spp.dn.exr")
        );
        assert!(output_path(Path::new("a.exr")).is_none());
    }
}
