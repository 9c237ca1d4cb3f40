//! Channel names of AOV layers, in the conventions compositors expect: colours are
//! `R`, `G`, `B` (`A`), directions and positions `X`, `Y`, `Z` (`W`), depth is `Z` (as
//! Blender's `Depth.Z`), and any other single channel is `Y`, OpenEXR's greyscale.

/// Layers whose values are vectors rather than colours.
const VECTOR_LAYERS: [&str; 6] = [
    "normal", "position", "motion", "velocity", "tangent", "vector",
];
/// Single-channel layers that hold a distance.
const DEPTH_LAYERS: [&str; 3] = ["depth", "z", "mist"];

/// The full channel names (`"<layer>.<channel>"`) of an AOV with `channels` channels.
pub fn channel_names(layer: &str, channels: u32) -> Vec<String> {
    let lower = layer.to_ascii_lowercase();
    let vector = VECTOR_LAYERS.iter().any(|v| lower.contains(v));
    let suffixes: Vec<String> = match channels {
        1 if DEPTH_LAYERS.contains(&lower.as_str()) => vec!["Z".into()],
        1 => vec!["Y".into()],
        2 => vec!["X".into(), "Y".into()],
        3 | 4 if vector => ["X", "Y", "Z", "W"][..channels as usize]
            .iter()
            .map(|s| (*s).to_owned())
            .collect(),
        3 | 4 => ["R", "G", "B", "A"][..channels as usize]
            .iter()
            .map(|s| (*s).to_owned())
            .collect(),
        n => (0..n).map(|i| i.to_string()).collect(),
    };
    suffixes
        .into_iter()
        .map(|s| format!("{layer}.{s}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn common_aovs_get_the_conventional_channel_names() {
        assert_eq!(
            channel_names("albedo", 3),
            ["albedo.R", "albedo.G", "albedo.B"]
        );
        assert_eq!(
            channel_names("normal", 3),
            ["normal.X", "normal.Y", "normal.Z"]
        );
        assert_eq!(channel_names("depth", 1), ["depth.Z"]);
        assert_eq!(channel_names("coverage", 1), ["coverage.Y"]);
        assert_eq!(
            channel_names("beauty", 4),
            ["beauty.R", "beauty.G", "beauty.B", "beauty.A"]
        );
        assert_eq!(channel_names("extra", 5).len(), 5);
    }
}
