//! The part of a split render (`kiln render --samples A..B`) and the merge of parts
//! (`kiln merge`).
//!
//! A part is an OpenEXR file any viewer opens: its `R`, `G`, `B` channels are the mean
//! radiance of the samples it holds. Beside them it keeps the film exactly as the device
//! accumulated it ([`ExactFilm`]): each pixel's fixed-point sums as 32-bit words
//! (`kiln.sum.Rlo`, `kiln.sum.Rhi`, … as `UINT` channels) and its sample count
//! (`kiln.count.N`). Its header names what the samples belong to ([`PartHeader`]), so that
//! a merge takes only parts of one render. Integer sums add exactly, in any order: the
//! merged film is the very film one process rendering every sample would hold, and the
//! image made from it the same bits.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Blocks, Compression, Encoding, FlatSamples, Image,
    Layer, LayerAttributes, LineOrder, SmallVec, Text, Vec2, WritableImage,
};

use crate::film::ExactFilm;
use crate::film::output::ViewSettings;
use crate::film::tonemap::Tonemap;
use crate::render::{RenderSettings, checkpoint};
use crate::scene::Scene;

/// The header attributes' prefix.
const PREFIX: &str = "kiln.";
/// The part format's version, in the header as `kiln.partFormat`.
const FORMAT: u32 = 1;

/// What a part's samples belong to, written into its header.
#[derive(Clone, Debug, PartialEq)]
pub struct PartHeader {
    /// The sample indices every pixel holds.
    pub samples: Range<u32>,
    /// The samples per pixel of the whole render: the parts together cover `0..total`.
    pub total_samples: u32,
    pub seed: u32,
    /// The sampler's key (`sobol`, `independent`).
    pub sampler: String,
    /// [`scene_hash`] of the scene rendered.
    pub scene_hash: u64,
    /// [`settings_hash`] of the settings it was rendered with.
    pub settings_hash: u64,
    /// The frame of an animation, if the render is one.
    pub frame: Option<u32>,
    /// How the merged image is viewed (a PNG's tonemap and exposure).
    pub view: ViewSettings,
}

/// The hash of everything in the scene (geometry, materials, lights, camera).
pub fn scene_hash(scene: &Scene) -> u64 {
    checkpoint::debug_hash(scene)
}

/// The hash of the settings that decide a sample's value ([`checkpoint::settings_hash`]).
pub fn settings_hash(settings: &RenderSettings) -> u64 {
    checkpoint::settings_hash(settings)
}

impl PartHeader {
    fn attributes(&self) -> Vec<(&'static str, String)> {
        let mut list = vec![
            ("partFormat", FORMAT.to_string()),
            (
                "samples",
                format!("{}..{}", self.samples.start, self.samples.end),
            ),
            ("totalSamples", self.total_samples.to_string()),
            ("seed", self.seed.to_string()),
            ("sampler", self.sampler.clone()),
            ("sceneHash", format!("{:016x}", self.scene_hash)),
            ("settingsHash", format!("{:016x}", self.settings_hash)),
            ("exposure", self.view.exposure_ev.to_string()),
            ("tonemap", self.view.tonemap.key().to_owned()),
        ];
        if let Some(frame) = self.frame {
            list.push(("frame", frame.to_string()));
        }
        list
    }

    fn from_attributes(other: &HashMap<Text, AttributeValue>) -> Result<Self, String> {
        let text = |name: &str| -> Result<String, String> {
            match other.get(&Text::from(format!("{PREFIX}{name}").as_str())) {
                Some(AttributeValue::Text(t)) => Ok(t.to_string()),
                Some(_) => Err(format!("its {PREFIX}{name} attribute is not text")),
                None => Err(format!("it has no {PREFIX}{name} attribute")),
            }
        };
        let number = |name: &str| -> Result<u32, String> {
            let t = text(name)?;
            t.parse()
                .map_err(|_| format!("its {PREFIX}{name} \"{t}\" is not a whole number"))
        };
        let hash = |name: &str| -> Result<u64, String> {
            let t = text(name)?;
            u64::from_str_radix(&t, 16)
                .map_err(|_| format!("its {PREFIX}{name} \"{t}\" is not a hash"))
        };
        if !other.contains_key(&Text::from("kiln.partFormat")) {
            return Err("it is not the part of a split render (kiln render --samples)".into());
        }
        let format = number("partFormat")?;
        if format != FORMAT {
            return Err(format!(
                "it is a part of format {format}; this Kiln reads {FORMAT}"
            ));
        }
        let samples = parse_range(&text("samples")?)?;
        let tonemap_key = text("tonemap")?;
        let tonemap = Tonemap::ALL
            .into_iter()
            .find(|t| t.key() == tonemap_key)
            .ok_or_else(|| format!("its tonemap \"{tonemap_key}\" is unknown"))?;
        let exposure = text("exposure")?;
        Ok(Self {
            samples,
            total_samples: number("totalSamples")?,
            seed: number("seed")?,
            sampler: text("sampler")?,
            scene_hash: hash("sceneHash")?,
            settings_hash: hash("settingsHash")?,
            frame: match text("frame") {
                Ok(_) => Some(number("frame")?),
                Err(_) => None,
            },
            view: ViewSettings {
                exposure_ev: exposure
                    .parse()
                    .map_err(|_| format!("its exposure \"{exposure}\" is not a number"))?,
                tonemap,
            },
        })
    }
}

/// Parses a range of sample indices or frames, `A..B` (B excluded), as Rust writes it.
pub fn parse_range(s: &str) -> Result<Range<u32>, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("\"{s}\" is not a range A..B"))?;
    let number = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|_| format!("\"{s}\": \"{t}\" is not a whole number"))
    };
    let (a, b) = (number(a)?, number(b)?);
    if a >= b {
        return Err(format!(
            "\"{s}\" is empty: A..B takes A up to B, B excluded"
        ));
    }
    Ok(a..b)
}

/// The channels of a part: the mean radiance, the fixed-point sums and the counts.
fn part_channels(film: &ExactFilm) -> SmallVec<[AnyChannel<FlatSamples>; 4]> {
    let mean = film.to_film().radiance();
    let named = |name: &str, samples| AnyChannel::new(Text::from(name), samples);
    let mut list = SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        list.push(named(
            name,
            FlatSamples::F32(mean.iter().map(|m| m[c]).collect()),
        ));
        let words = |high: bool| {
            film.sums
                .iter()
                .map(|s| {
                    if high {
                        (s[c] >> 32) as u32
                    } else {
                        s[c] as u32
                    }
                })
                .collect()
        };
        list.push(named(
            &format!("kiln.sum.{name}lo"),
            FlatSamples::U32(words(false)),
        ));
        list.push(named(
            &format!("kiln.sum.{name}hi"),
            FlatSamples::U32(words(true)),
        ));
    }
    list.push(named("kiln.count.N", FlatSamples::U32(film.counts.clone())));
    list
}

/// Writes a part atomically: a crash or a full disk leaves no half-written part.
pub fn write_part(path: &Path, header: &PartHeader, film: &ExactFilm) -> Result<(), String> {
    let mut attributes = LayerAttributes::default();
    for (name, value) in header.attributes() {
        attributes.other.insert(
            Text::from(format!("{PREFIX}{name}").as_str()),
            AttributeValue::Text(Text::from(value.as_str())),
        );
    }
    let layer = Layer::new(
        Vec2(film.width as usize, film.height as usize),
        attributes,
        Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(part_channels(film)),
    );
    let image = Image::from_layer(layer);
    kiln_plugin_api::atomic::write_atomically(path, |writer| {
        image.write().to_buffered(writer).map_err(|e| e.to_string())
    })
    .map_err(|e| format!("cannot write the part {}: {e}", path.display()))
}

/// Reads the header of a part, not its pixels.
pub fn read_part_header(path: &Path) -> Result<PartHeader, String> {
    let fail = |why: String| format!("{} is not a usable part: {why}", path.display());
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| fail(e.to_string()))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| fail("it has no image".into()))?;
    PartHeader::from_attributes(&header.own_attributes.other).map_err(fail)
}

/// Reads a part: its header and its exact film.
pub fn read_part(path: &Path) -> Result<(PartHeader, ExactFilm), String> {
    let fail = |why: String| format!("{} is not a usable part: {why}", path.display());
    let header = read_part_header(path)?;
    let image =
        exr::prelude::read_first_flat_layer_from_file(path).map_err(|e| fail(e.to_string()))?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.0 as u32, layer.size.1 as u32);
    let words = |name: &str| -> Result<&Vec<u32>, String> {
        let channel = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .ok_or_else(|| fail(format!("it has no {name} channel")))?;
        match &channel.sample_data {
            FlatSamples::U32(v) => Ok(v),
            _ => Err(fail(format!("its {name} channel is not 32-bit integers"))),
        }
    };
    let mut film = ExactFilm::new(width, height);
    film.counts.clone_from(words("kiln.count.N")?);
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let low = words(&format!("kiln.sum.{name}lo"))?;
        let high = words(&format!("kiln.sum.{name}hi"))?;
        for (i, (l, h)) in low.iter().zip(high).enumerate() {
            film.sums[i][c] = ExactFilm::join(*l, *h);
        }
    }
    let expected = header.samples.len() as u32;
    if let Some(i) = film.counts.iter().position(|&n| n != expected) {
        return Err(fail(format!(
            "pixel ({}, {}) holds {} samples, its range {}..{} has {expected}",
            i as u32 % width.max(1),
            i as u32 / width.max(1),
            film.counts[i],
            header.samples.start,
            header.samples.end
        )));
    }
    Ok((header, film))
}

/// What is wrong with a set of parts, or what a partial merge lacks.
#[derive(Debug, Default, PartialEq)]
pub struct Coverage {
    /// Sample ranges no part holds.
    pub missing: Vec<Range<u32>>,
}

/// Checks that `parts` belong to one render and that their ranges are disjoint; returns
/// the ranges of `0..total` they leave out. Errors name the parts that disagree.
pub fn check_parts(parts: &[(PathBuf, PartHeader)]) -> Result<Coverage, String> {
    let Some((first_path, first)) = parts.first() else {
        return Err("no parts to merge".into());
    };
    for (path, p) in &parts[1..] {
        let differs = |what: &str| {
            format!(
                "{} and {} are not parts of one render: their {what} differ",
                first_path.display(),
                path.display()
            )
        };
        if p.scene_hash != first.scene_hash {
            return Err(differs("scenes"));
        }
        if p.settings_hash != first.settings_hash {
            return Err(differs("settings"));
        }
        if p.seed != first.seed {
            return Err(differs("seeds"));
        }
        if p.sampler != first.sampler {
            return Err(differs("samplers"));
        }
        if p.total_samples != first.total_samples {
            return Err(differs("total samples per pixel"));
        }
        if p.frame != first.frame {
            return Err(differs("frames"));
        }
    }
    let mut sorted: Vec<&(PathBuf, PartHeader)> = parts.iter().collect();
    sorted.sort_by_key(|(_, p)| (p.samples.start, p.samples.end));
    let mut coverage = Coverage::default();
    let mut next = 0;
    let mut previous: Option<&(PathBuf, PartHeader)> = None;
    for part in sorted {
        let (path, p) = part;
        if p.samples.end > first.total_samples {
            return Err(format!(
                "{} holds samples {}..{}, past the render's {} samples per pixel",
                path.display(),
                p.samples.start,
                p.samples.end,
                first.total_samples
            ));
        }
        if p.samples.start < next {
            let (other, q) = previous.expect("a range ends at `next`");
            return Err(format!(
                "{} (samples {}..{}) and {} (samples {}..{}) overlap",
                other.display(),
                q.samples.start,
                q.samples.end,
                path.display(),
                p.samples.start,
                p.samples.end
            ));
        }
        if p.samples.start > next {
            coverage.missing.push(next..p.samples.start);
        }
        next = p.samples.end;
        previous = Some(part);
    }
    if next < first.total_samples {
        coverage.missing.push(next..first.total_samples);
    }
    Ok(coverage)
}

/// Sample ranges as a list for a message: `16..32, 48..64`.
pub fn describe_ranges(ranges: &[Range<u32>]) -> String {
    ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The parts at `paths` merged: their common header (samples: those merged) and film.
/// Missing sample ranges are an error unless `allow_partial`; then they are returned.
pub fn merge_parts(
    paths: &[PathBuf],
    allow_partial: bool,
) -> Result<(PartHeader, ExactFilm, Coverage), String> {
    let headers = paths
        .iter()
        .map(|p| Ok((p.clone(), read_part_header(p)?)))
        .collect::<Result<Vec<_>, String>>()?;
    let coverage = check_parts(&headers)?;
    if !coverage.missing.is_empty() && !allow_partial {
        return Err(format!(
            "samples {} of {} per pixel are in none of the parts (--allow-partial merges what is there)",
            describe_ranges(&coverage.missing),
            headers[0].1.total_samples
        ));
    }
    let mut merged: Option<(PartHeader, ExactFilm)> = None;
    for path in paths {
        let (header, film) = read_part(path)?;
        match &mut merged {
            None => merged = Some((header, film)),
            Some((_, total)) => total
                .merge(&film)
                .map_err(|e| format!("cannot merge {}: {e}", path.display()))?,
        }
    }
    let (mut header, film) = merged.expect("at least one part");
    header.samples = 0..header.total_samples;
    Ok((header, film, coverage))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(samples: Range<u32>) -> PartHeader {
        PartHeader {
            samples,
            total_samples: 64,
            seed: 3,
            sampler: "sobol".into(),
            scene_hash: 1,
            settings_hash: 2,
            frame: None,
            view: ViewSettings::default(),
        }
    }

    fn parts(ranges: &[Range<u32>]) -> Vec<(PathBuf, PartHeader)> {
        ranges
            .iter()
            .enumerate()
            .map(|(i, r)| (PathBuf::from(format!("p{i}.exr")), header(r.clone())))
            .collect()
    }

    #[test]
    fn ranges_parse_as_rust_writes_them() {
        assert_eq!(parse_range("16..32"), Ok(16..32));
        assert!(parse_range("32..16").unwrap_err().contains("empty"));
        assert!(parse_range("16-32").unwrap_err().contains("not a range"));
        assert!(parse_range("a..3").unwrap_err().contains("\"a\""));
    }

    #[test]
    fn coverage_names_gaps_and_overlaps() {
        let whole = check_parts(&parts(&[32..64, 0..16, 16..32])).unwrap();
        assert!(whole.missing.is_empty());
        let gaps = check_parts(&parts(&[16..32, 48..60])).unwrap();
        assert_eq!(gaps.missing, vec![0..16, 32..48, 60..64]);
        let overlap = check_parts(&parts(&[0..20, 16..64])).unwrap_err();
        assert!(
            overlap.contains("p0.exr (samples 0..20) and p1.exr (samples 16..64) overlap"),
            "{overlap}"
        );
        let mut other = parts(&[0..32, 32..64]);
        other[1].1.seed = 4;
        assert!(check_parts(&other).unwrap_err().contains("seeds differ"));
        let past = check_parts(&parts(&[0..40, 40..80])).unwrap_err();
        assert!(past.contains("past the render's 64"), "{past}");
    }

    #[test]
    fn a_part_keeps_its_film_and_header_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.exr");
        let mut film = ExactFilm::new(3, 2);
        for (i, s) in film.sums.iter_mut().enumerate() {
            *s = [i as i64 - 2, i64::MAX - i as i64, (i as i64) << 40];
        }
        film.counts = vec![16; 6];
        let mut h = header(16..32);
        h.frame = Some(7);
        h.view.exposure_ev = -1.5;
        write_part(&path, &h, &film).unwrap();
        assert_eq!(read_part(&path).unwrap(), (h, film));
        let wrong = dir.path().join("wrong.exr");
        let mut short = ExactFilm::new(1, 1);
        short.counts = vec![3];
        write_part(&wrong, &header(0..4), &short).unwrap();
        let e = read_part(&wrong).unwrap_err();
        assert!(e.contains("pixel (0, 0) holds 3 samples"), "{e}");
    }
}
