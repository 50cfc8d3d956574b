//! Species parameters of Weber & Penn, "Creation and Rendering of Realistic Trees"
//! (SIGGRAPH 1995), kept under their names in human-readable TOML species files.
//!
//! A species file is flat TOML: `Shape = 7`, `BaseSize = 0.4`, … and per-level keys with the
//! level digit first, `0Length = 1.0`, `1DownAngle = 60`, … (levels 0–3; level 0 is the
//! trunk). [`PARAMS`] documents every key: meaning, unit and valid range. Missing keys take
//! the default listed there. Reading reports the first problem with the key and the line:
//! unknown key, wrong type, out-of-range value, or an empty file.

use std::fmt;

use thiserror::Error;

/// Where a parameter lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// A whole-tree parameter.
    Global,
    /// A per-level parameter (the key is prefixed by the level digit 0–3).
    Level,
}

/// Documentation and range of one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamDoc {
    /// WP95 name (per-level names without the digit).
    pub name: &'static str,
    /// Global or per level.
    pub scope: Scope,
    /// Unit ("" for none).
    pub unit: &'static str,
    /// Smallest valid value.
    pub min: f32,
    /// Largest valid value.
    pub max: f32,
    /// Whether the value must be a whole number.
    pub integer: bool,
    /// Default when the key is missing.
    pub default: f32,
    /// Meaning.
    pub doc: &'static str,
}

/// Mutable storage of one parameter.
enum Slot<'a> {
    F(&'a mut f32),
    U(&'a mut u32),
}

/// A field type a species parameter may have: `f32`, or `u32` for whole numbers.
trait ParamField {
    /// Whether values must be whole numbers.
    const INTEGER: bool;
    fn slot(&mut self) -> Slot<'_>;
}
impl ParamField for f32 {
    const INTEGER: bool = false;
    fn slot(&mut self) -> Slot<'_> {
        Slot::F(self)
    }
}
impl ParamField for u32 {
    const INTEGER: bool = true;
    fn slot(&mut self) -> Slot<'_> {
        Slot::U(self)
    }
}

/// The one table of species parameters. Each row — field, type, WP95 name, unit, range,
/// default and meaning — becomes the struct field (documented by the row), its [`PARAMS`]
/// entry (parsing, range checks, defaults, `sylva tree params`) and its name in the lookup
/// that `set`/`get` use: adding a parameter is one row here (and the code that uses it).
macro_rules! species_params {
    (
        global { $( $gf:ident : $gt:ident = $gname:literal, $gunit:literal,
                    $gmin:literal ..= $gmax:literal, $gdef:literal, $gdoc:literal; )* }
        level { $( $lf:ident : $lt:ident = $lname:literal, $lunit:literal,
                   $lmin:literal ..= $lmax:literal, $ldef:literal, $ldoc:literal; )* }
    ) => {
        /// Parameters of one recursion level (WP95 "n" parameters; each field's doc names the
        /// key without its level digit).
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct LevelParams {
            $( #[doc = concat!("`n", $lname, "`: ", $ldoc, " (unit and range: [`PARAMS`]).")] pub $lf: $lt, )*
        }

        /// A Weber–Penn species.
        #[derive(Debug, Clone, PartialEq, Default)]
        pub struct Species {
            /// Name (from the file name or the preset).
            pub name: String,
            $( #[doc = concat!("`", $gname, "`: ", $gdoc, " (unit and range: [`PARAMS`]).")] pub $gf: $gt, )*
            /// Per-level parameters, levels 0–3.
            pub level: [LevelParams; 4],
        }

        /// Every parameter of a species file (whole-tree ones first, then per-level ones).
        pub const PARAMS: &[ParamDoc] = &[
            $( ParamDoc {
                name: $gname, scope: Scope::Global, unit: $gunit, min: $gmin as f32,
                max: $gmax as f32, integer: <$gt as ParamField>::INTEGER, default: $gdef as f32,
                doc: $gdoc,
            }, )*
            $( ParamDoc {
                name: $lname, scope: Scope::Level, unit: $lunit, min: $lmin as f32,
                max: $lmax as f32, integer: <$lt as ParamField>::INTEGER, default: $ldef as f32,
                doc: $ldoc,
            }, )*
        ];

        impl Species {
            /// The storage of a parameter, by WP95 name (per-level names without the digit).
            fn slot(&mut self, level: Option<usize>, name: &str) -> Option<Slot<'_>> {
                match level {
                    Some(n) => {
                        let lp = self.level.get_mut(n)?;
                        match name {
                            $( $lname => Some(lp.$lf.slot()), )*
                            _ => None,
                        }
                    }
                    None => match name {
                        $( $gname => Some(self.$gf.slot()), )*
                        _ => None,
                    },
                }
            }
        }
    };
}

species_params! {
    global {
        shape: u32 = "Shape", "", 0 ..= 8, 4,
            "crown envelope: 0 conical, 1 spherical, 2 hemispherical, 3 cylindrical, 4 tapered cylindrical, 5 flame, 6 inverse conical, 7 tend flame, 8 pruning envelope";
        base_size: f32 = "BaseSize", "", 0.0 ..= 1.0, 0.25, "fraction of the trunk below the first branch";
        scale: f32 = "Scale", "m", 0.1 ..= 150.0, 10.0, "tree size";
        scale_v: f32 = "ScaleV", "m", 0.0 ..= 100.0, 0.0, "variation of Scale";
        z_scale: f32 = "ZScale", "", 0.0 ..= 10.0, 1.0, "vertical scaling";
        z_scale_v: f32 = "ZScaleV", "", 0.0 ..= 10.0, 0.0, "variation of ZScale";
        levels: u32 = "Levels", "", 1 ..= 4, 3, "recursion depth: trunk, branches, sub-branches, twigs";
        max_joints: u32 = "MaxJoints", "joints", 1000 ..= 16_000_000, 1_000_000,
            "guard: the most joints a tree may grow (about 1 kB of memory each with its mesh); \
             generation is refused beyond it, before growing when the branch counts already \
             exceed it; the weeping willow grows 36 000";
        ratio: f32 = "Ratio", "", 0.001 ..= 0.5, 0.015, "trunk base radius divided by tree length";
        ratio_power: f32 = "RatioPower", "", 0.0 ..= 5.0, 1.2,
            "child radius = parent radius × (child length / parent length)^RatioPower";
        lobes: u32 = "Lobes", "", 0 ..= 20, 0, "lobes of the trunk cross-section";
        lobe_depth: f32 = "LobeDepth", "", 0.0 ..= 1.0, 0.0, "depth of the lobes, relative to the radius";
        flare: f32 = "Flare", "", 0.0 ..= 10.0, 0.5, "widening of the trunk base, relative to its radius";
        scale0: f32 = "0Scale", "", 0.01 ..= 10.0, 1.0, "trunk radius scale";
        scale0_v: f32 = "0ScaleV", "", 0.0 ..= 10.0, 0.0, "variation of 0Scale";
        base_splits: u32 = "0BaseSplits", "", 0 ..= 10, 0, "clones made at the trunk base (one split level)";
        leaves: f32 = "Leaves", "per stem", -20000.0 ..= 20000.0, 20.0,
            "leaves on each last-level stem (negative: fan at the tip)";
        leaf_shape: u32 = "LeafShape", "", 0 ..= 8, 0,
            "leaf outline: 0 elliptic, 1 lanceolate, 2 ovate, 3 rounded with a pointed tip, 4 lobed, 5 palmate, 6 needle, 7 round, 8 heart";
        leaf_scale: f32 = "LeafScale", "m", 0.001 ..= 5.0, 0.15, "leaf length";
        leaf_scale_x: f32 = "LeafScaleX", "", 0.01 ..= 5.0, 0.7, "leaf width / length";
        attraction_up: f32 = "AttractionUp", "", -10.0 ..= 10.0, 0.0,
            "bend of stems towards the sky (negative: droop)";
        prune_ratio: f32 = "PruneRatio", "", 0.0 ..= 1.0, 0.0, "0 no pruning, 1 stems cut to the envelope";
        prune_width: f32 = "PruneWidth", "", 0.01 ..= 10.0, 0.5, "envelope width relative to the tree height";
        prune_width_peak: f32 = "PruneWidthPeak", "", 0.0 ..= 1.0, 0.5,
            "relative height of the envelope's widest point";
        prune_power_low: f32 = "PrunePowerLow", "", 0.0 ..= 10.0, 0.5, "curvature of the envelope below its peak";
        prune_power_high: f32 = "PrunePowerHigh", "", 0.0 ..= 10.0, 0.5, "curvature of the envelope above its peak";
        leaf_quality: f32 = "LeafQuality", "", 0.01 ..= 1.0, 1.0,
            "fraction of leaves generated (the rest enlarge to keep the area)";
        bark_shade: f32 = "BarkShade", "", 0.0 ..= 1.0, 0.3, "bark colour: 0 dark brown … 1 pale (Sylva)";
        bark_roughness: f32 = "BarkRoughness", "", 0.0 ..= 1.0, 0.6, "bark: 0 smooth … 1 deep furrows (Sylva)";
        leaf_shade: f32 = "LeafShade", "", 0.0 ..= 1.0, 0.5,
            "foliage: 0 dark blue-green … 1 light yellow-green (Sylva)";
    }
    level {
        length: f32 = "Length", "", 0.0 ..= 10.0, 0.5,
            "stem length relative to the parent (level 0: to the tree size)";
        length_v: f32 = "LengthV", "", 0.0 ..= 10.0, 0.0, "variation of Length";
        taper: f32 = "Taper", "", 0.0 ..= 3.0, 1.0, "0 cylinder, 1 cone, 1–2 rounded tip, 2–3 periodic";
        seg_splits: f32 = "SegSplits", "per segment", 0.0 ..= 2.0, 0.0,
            "splits per segment, fractions carried forward as an error term";
        split_angle: f32 = "SplitAngle", "°", 0.0 ..= 180.0, 0.0, "angle between split stems";
        split_angle_v: f32 = "SplitAngleV", "°", 0.0 ..= 180.0, 0.0, "variation of SplitAngle";
        curve_res: u32 = "CurveRes", "segments", 1 ..= 64, 3, "segments per stem";
        curve: f32 = "Curve", "°", -360.0 ..= 360.0, 0.0, "total curvature along the stem";
        curve_back: f32 = "CurveBack", "°", -360.0 ..= 360.0, 0.0,
            "curvature of the upper half (S-curve); 0 for none";
        curve_v: f32 = "CurveV", "°", -720.0 ..= 720.0, 0.0, "random curvature per stem; negative: helix";
        down_angle: f32 = "DownAngle", "°", -180.0 ..= 180.0, 45.0, "angle between a child and its parent's axis";
        down_angle_v: f32 = "DownAngleV", "°", -180.0 ..= 180.0, 0.0,
            "variation of DownAngle (negative: varies along the parent)";
        rotate: f32 = "Rotate", "°", -360.0 ..= 360.0, 140.0,
            "rotation between successive children (negative: alternating)";
        rotate_v: f32 = "RotateV", "°", 0.0 ..= 360.0, 0.0, "variation of Rotate";
        branches: f32 = "Branches", "per stem", 0.0 ..= 2000.0, 0.0, "children per parent stem";
    }
}

/// A species file that cannot be used.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpeciesError {
    /// Neither a preset nor a readable file.
    #[error(
        "no preset named `{name}` and no readable species file of that name ({reason}); presets: {presets}"
    )]
    NotFound {
        /// What was asked for.
        name: String,
        /// Why reading it as a file failed.
        reason: String,
        /// The shipped presets, comma-separated.
        presets: String,
    },
    /// The file is empty.
    #[error("{file}: the species file is empty")]
    Empty {
        /// File name.
        file: String,
    },
    /// TOML syntax error.
    #[error("{file}: line {line}, column {column}: {message}")]
    Syntax {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column (characters) within the line.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A key that is not a species parameter.
    #[error("{file}: line {line}: unknown parameter `{key}`")]
    UnknownKey {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key.
        key: String,
    },
    /// A value of the wrong type.
    #[error("{file}: line {line}: parameter `{key}` must be a number, found {found}")]
    WrongType {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key.
        key: String,
        /// What was found.
        found: String,
    },
    /// A value outside its range.
    #[error("{file}: line {line}: parameter `{key}` = {value} is out of range ({range})")]
    OutOfRange {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key.
        key: String,
        /// The value.
        value: f64,
        /// The valid range.
        range: String,
    },
}

/// The 1-based line where `key` is set (`key = …`) or opens a table (`[key]`, `[[key]]`,
/// `[key.sub]`); 0 if neither is found.
fn line_of(text: &str, key: &str) -> usize {
    text.lines()
        .position(|l| {
            let t = l.trim_start();
            if let Some(header) = t.strip_prefix('[') {
                let h = header.trim_start_matches('[').trim_start();
                let h = h.strip_prefix('"').unwrap_or(h);
                return h.strip_prefix(key).is_some_and(|r| {
                    let r = r.strip_prefix('"').unwrap_or(r).trim_start();
                    r.starts_with(']') || r.starts_with('.')
                });
            }
            let t = t.strip_prefix('"').unwrap_or(t);
            t.strip_prefix(key).is_some_and(|r| {
                let r = r.strip_prefix('"').unwrap_or(r).trim_start();
                r.starts_with('=')
            })
        })
        .map_or(0, |i| i + 1)
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_and_column(text: &str, offset: usize) -> (usize, usize) {
    let mut at = offset.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Split a key into (level, base name): `1DownAngle` → (Some(1), "DownAngle").
fn split_key(key: &str) -> (Option<usize>, &str) {
    match key.as_bytes().first() {
        Some(d @ b'0'..=b'3')
            if PARAMS.iter().any(|p| p.scope == Scope::Level && p.name == &key[1..]) =>
        {
            (Some((d - b'0') as usize), &key[1..])
        }
        _ => (None, key),
    }
}

impl Species {
    /// A species with every parameter at its documented default.
    pub fn defaults(name: &str) -> Species {
        // Every field is a row of `species_params!`, whose defaults fill it.
        let mut s = Species { name: name.into(), ..Species::default() };
        for p in PARAMS {
            match p.scope {
                Scope::Global => s.set(None, p.name, p.default),
                Scope::Level => (0..4).for_each(|n| s.set(Some(n), p.name, p.default)),
            }
        }
        s
    }

    /// Set a parameter by WP95 name (per-level names without the digit; level 0–3).
    /// Unknown names are ignored (callers check against [`PARAMS`] first).
    pub fn set(&mut self, level: Option<usize>, name: &str, v: f32) {
        match self.slot(level, name) {
            Some(Slot::F(f)) => *f = v,
            Some(Slot::U(u)) => *u = v as u32,
            None => {}
        }
    }

    /// Read a parameter by WP95 name (0 for an unknown name).
    pub fn get(&self, level: Option<usize>, name: &str) -> f32 {
        // One name table (`slot`) serves reading and writing; a species is small to copy.
        match self.clone().slot(level, name) {
            Some(Slot::F(f)) => *f,
            Some(Slot::U(u)) => *u as f32,
            None => 0.0,
        }
    }

    /// Parse a species file's text. `file` names it in errors.
    pub fn from_toml(file: &str, text: &str) -> Result<Species, SpeciesError> {
        if text.trim().is_empty() {
            return Err(SpeciesError::Empty { file: file.into() });
        }
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, column) = e.span().map_or((0, 0), |s| line_and_column(text, s.start));
            let message = e.message().trim().to_string();
            SpeciesError::Syntax { file: file.into(), line, column, message }
        })?;
        let name = std::path::Path::new(file).file_stem().and_then(|s| s.to_str()).unwrap_or(file);
        let mut s = Species::defaults(name);
        for (key, value) in &table {
            let line = line_of(text, key);
            let (level, base) = split_key(key);
            let Some(doc) = PARAMS
                .iter()
                .find(|p| p.name == base && (p.scope == Scope::Level) == level.is_some())
            else {
                return Err(SpeciesError::UnknownKey { file: file.into(), line, key: key.clone() });
            };
            let v = match value {
                toml::Value::Integer(i) => *i as f64,
                toml::Value::Float(f) => *f,
                other => {
                    return Err(SpeciesError::WrongType {
                        file: file.into(),
                        line,
                        key: key.clone(),
                        found: format!("a {}", other.type_str()),
                    });
                }
            };
            let in_range = v.is_finite() && v >= doc.min as f64 && v <= doc.max as f64;
            if !in_range || (doc.integer && v.fract() != 0.0) {
                let kind = if doc.integer { "a whole number" } else { "a number" };
                return Err(SpeciesError::OutOfRange {
                    file: file.into(),
                    line,
                    key: key.clone(),
                    value: v,
                    range: format!(
                        "{kind} in [{}, {}]{}",
                        doc.min,
                        doc.max,
                        if doc.unit.is_empty() { String::new() } else { format!(" {}", doc.unit) }
                    ),
                });
            }
            s.set(level, base, v as f32);
        }
        Ok(s)
    }

    /// The species as a TOML species file (every parameter, WP95 names).
    pub fn to_toml(&self) -> String {
        let mut out =
            format!("# {} — Weber & Penn (1995) parameters; see `sylva tree params`\n", self.name);
        for p in PARAMS.iter().filter(|p| p.scope == Scope::Global) {
            out += &format!("{} = {}\n", p.name, self.get(None, p.name));
        }
        for n in 0..4 {
            out += &format!("\n# level {n}\n");
            for p in PARAMS.iter().filter(|p| p.scope == Scope::Level) {
                out += &format!("{n}{} = {}\n", p.name, self.get(Some(n), p.name));
            }
        }
        out
    }
}

impl fmt::Display for Species {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_toml())
    }
}

/// The species shipped with Sylva: (name, species file text).
pub const PRESETS: &[(&str, &str)] = &[
    ("quaking_aspen", include_str!("../presets/quaking_aspen.toml")),
    ("black_tupelo", include_str!("../presets/black_tupelo.toml")),
    ("weeping_willow", include_str!("../presets/weeping_willow.toml")),
    ("california_black_oak", include_str!("../presets/california_black_oak.toml")),
    ("douglas_fir", include_str!("../presets/douglas_fir.toml")),
    ("sugar_maple", include_str!("../presets/sugar_maple.toml")),
];

impl Species {
    /// A shipped species by name (`quaking_aspen`, …; see [`PRESETS`]).
    pub fn preset(name: &str) -> Option<Species> {
        let (n, text) = PRESETS.iter().find(|(n, _)| *n == name)?;
        // The shipped files are checked by the tests; a failure here is a build defect.
        Species::from_toml(&format!("{n}.toml"), text).ok()
    }

    /// A preset by name, or else the species file at that path.
    pub fn load(name_or_path: &str) -> Result<Species, SpeciesError> {
        if let Some(sp) = Species::preset(name_or_path) {
            return Ok(sp);
        }
        let text = std::fs::read_to_string(name_or_path).map_err(|e| SpeciesError::NotFound {
            name: name_or_path.to_string(),
            reason: e.to_string(),
            presets: PRESETS.iter().map(|p| p.0).collect::<Vec<_>>().join(", "),
        })?;
        Species::from_toml(name_or_path, &text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `PARAMS` and `slot` reach every numeric field (a field added to the structs outside
    /// `species_params!` would be missed): setting every parameter (on every level) to 1
    /// leaves no field at its zero default, so `defaults` fills them all.
    #[test]
    fn every_field_is_a_parameter() {
        let mut s = Species::default();
        for p in PARAMS {
            match p.scope {
                Scope::Global => s.set(None, p.name, 1.0),
                Scope::Level => (0..4).for_each(|n| s.set(Some(n), p.name, 1.0)),
            }
        }
        let text = format!("{s:?}").replace(['{', '}', '[', ']'], ",");
        let zeros: Vec<&str> = text
            .split(',')
            .filter(|f| f.trim_end().ends_with(": 0") || f.trim_end().ends_with(": 0.0"))
            .collect();
        assert!(zeros.is_empty(), "fields no parameter sets: {zeros:?}");
    }

    #[test]
    fn load_takes_a_preset_name_or_a_file_and_names_what_is_missing() {
        assert_eq!(
            Species::load("douglas_fir"),
            Ok(Species::preset("douglas_fir").expect("preset"))
        );
        let e = Species::load("no/such/species.toml").expect_err("missing");
        let text = e.to_string();
        assert!(text.contains("no/such/species.toml") && text.contains("quaking_aspen"), "{text}");
    }

    #[test]
    fn every_preset_parses_and_round_trips() {
        for (name, text) in PRESETS {
            let s =
                Species::from_toml(&format!("{name}.toml"), text).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(&s.name, name);
            let again =
                Species::from_toml(&format!("{name}.toml"), &s.to_toml()).expect("round trip");
            assert_eq!(again, s);
        }
        let aspen = Species::preset("quaking_aspen").expect("shipped");
        // WP95 Table 1 values for the aspen.
        assert_eq!((aspen.shape, aspen.levels, aspen.scale, aspen.ratio), (7, 3, 13.0, 0.015));
        assert_eq!(aspen.level[1].branches, 50.0);
    }

    fn err(text: &str) -> String {
        Species::from_toml("bad.toml", text).expect_err("must be refused").to_string()
    }

    #[test]
    fn bad_files_name_the_parameter_and_the_line() {
        let e = err("Shape = 7\nLevls = 3\n");
        assert!(e.contains("Levls") && e.contains("line 2") && e.contains("unknown"), "{e}");
        let e = err("Shape = 7\n\nRatio = -0.5\n");
        assert!(e.contains("Ratio") && e.contains("line 3") && e.contains("range"), "{e}");
        let e = err("1Branches = \"many\"\n");
        assert!(e.contains("1Branches") && e.contains("line 1") && e.contains("string"), "{e}");
        let e = err("Levels = 2.5\n");
        assert!(e.contains("Levels") && e.contains("whole number"), "{e}");
        let e = err("4Length = 1\n");
        assert!(e.contains("4Length") && e.contains("unknown"), "{e}");
        let e = err("  \n\n");
        assert!(e.contains("empty"), "{e}");
        let e = err("Shape = = 3\n");
        assert!(e.contains("line 1"), "{e}");
    }
}
