//! MTL texture statements (`map_Kd -s 2 2 -bm 0.5 textures/wood.png`): the options the
//! MTL specification allows before the file name, and the file name itself, which may
//! contain spaces. Only the options that change how Kiln renders are kept.

/// Which channel of an image a scalar map reads (`-imfchan`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Red,
    Green,
    Blue,
    /// The matte (alpha) channel.
    Matte,
    /// Luminance; also what `z` (depth) maps to here.
    Luminance,
}

/// A parsed texture statement.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    /// As written, relative to the .obj's folder, with `\` turned into `/` (Windows
    /// exporters write backslashes, which other systems read as part of the name).
    pub file: String,
    /// `-bm`: bump multiplier.
    pub bump_multiplier: Option<f32>,
    /// `-s u v`: scales the texture coordinates.
    pub scale: Option<[f32; 2]>,
    /// `-o u v`: offsets the texture coordinates.
    pub offset: Option<[f32; 2]>,
    /// `-clamp on`: coordinates outside [0, 1] take the edge.
    pub clamp: bool,
    /// `-imfchan`: the channel scalar maps read.
    pub channel: Option<Channel>,
    /// Options that change the look but are not supported (`-mm`, `-t`).
    pub ignored: Vec<String>,
}

/// How many arguments an option takes.
enum Arity {
    One,
    Two,
    /// One to three numbers (`-o`, `-s`, `-t`: u [v [w]]).
    UpToThree,
}

fn arity(option: &str) -> Option<Arity> {
    Some(match option {
        "-bm" | "-boost" | "-texres" | "-clamp" | "-blendu" | "-blendv" | "-cc" | "-imfchan"
        | "-type" => Arity::One,
        "-mm" => Arity::Two,
        "-o" | "-s" | "-t" => Arity::UpToThree,
        _ => return None,
    })
}

/// Splits the first whitespace-separated word off `s` (already trimmed at the start).
fn word(s: &str) -> Option<(&str, &str)> {
    let end = s.find(char::is_whitespace).unwrap_or(s.len());
    (end > 0).then(|| (&s[..end], s[end..].trim_start()))
}

/// Parses a texture statement's arguments; `None` if it names no file.
pub fn parse_texture(statement: &str) -> Option<TextureRef> {
    let mut texture = TextureRef {
        file: String::new(),
        bump_multiplier: None,
        scale: None,
        offset: None,
        clamp: false,
        channel: None,
        ignored: Vec::new(),
    };
    let mut rest = statement.trim();
    while let Some((option, after)) = word(rest) {
        let Some(arity) = arity(option) else { break };
        rest = after;
        let mut args = Vec::new();
        match arity {
            Arity::One | Arity::Two => {
                let n = if matches!(arity, Arity::One) { 1 } else { 2 };
                for _ in 0..n {
                    let (arg, after) = word(rest)?;
                    args.push(arg);
                    rest = after;
                }
            }
            Arity::UpToThree => {
                while args.len() < 3 {
                    match word(rest) {
                        Some((arg, after)) if arg.parse::<f32>().is_ok() => {
                            args.push(arg);
                            rest = after;
                        }
                        _ => break,
                    }
                }
            }
        }
        let numbers: Vec<f32> = args
            .iter()
            .filter_map(|a| a.parse::<f32>().ok())
            .filter(|x| x.is_finite())
            .collect();
        match option {
            "-bm" => texture.bump_multiplier = numbers.first().copied(),
            "-s" if !numbers.is_empty() => {
                texture.scale = Some([numbers[0], numbers.get(1).copied().unwrap_or(1.0)])
            }
            "-o" if !numbers.is_empty() => {
                texture.offset = Some([numbers[0], numbers.get(1).copied().unwrap_or(0.0)])
            }
            "-clamp" => texture.clamp = args[0].eq_ignore_ascii_case("on"),
            "-imfchan" => {
                texture.channel = match args[0] {
                    "r" => Some(Channel::Red),
                    "g" => Some(Channel::Green),
                    "b" => Some(Channel::Blue),
                    "m" => Some(Channel::Matte),
                    _ => Some(Channel::Luminance),
                }
            }
            "-mm" | "-t" => texture.ignored.push(option.to_owned()),
            // -boost, -texres, -blendu/v, -cc, -type: no effect on a path tracer's lookup.
            _ => {}
        }
    }
    let file = rest.trim();
    if file.is_empty() {
        return None;
    }
    texture.file = file.replace('\\', "/");
    Some(texture)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_file_names_keep_their_spaces() {
        let t = parse_texture("textures/old wood.png").unwrap();
        assert_eq!(t.file, "textures/old wood.png");
        assert_eq!(t.bump_multiplier, None);
    }

    #[test]
    fn options_before_the_file_are_read() {
        let t =
            parse_texture("-bm 0.5 -s 2 3 1 -o 0.25 -clamp on -imfchan r -mm 0 1 h.png").unwrap();
        assert_eq!(t.file, "h.png");
        assert_eq!(t.bump_multiplier, Some(0.5));
        assert_eq!(t.scale, Some([2.0, 3.0]));
        assert_eq!(t.offset, Some([0.25, 0.0]));
        assert!(t.clamp);
        assert_eq!(t.channel, Some(Channel::Red));
        assert_eq!(t.ignored, ["-mm"]);
    }

    #[test]
    fn backslashes_become_slashes_and_options_alone_name_no_file() {
        assert_eq!(
            parse_texture(r"maps\wood.jpg").unwrap().file,
            "maps/wood.jpg"
        );
        assert_eq!(parse_texture("-bm 2"), None);
        assert_eq!(parse_texture("   "), None);
    }
}
