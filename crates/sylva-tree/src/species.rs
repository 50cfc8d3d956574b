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

/// Parameters of one recursion level (WP95 "n" parameters).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LevelParams {
    /// nLength: length of these stems relative to their parent's (level 0: to the tree).
    pub length: f32,
    /// nLengthV: variation of `length`.
    pub length_v: f32,
    /// nTaper: 0 cylinder, 1 cone, 1–2 spherical ends, 2–3 periodic.
    pub taper: f32,
    /// nSegSplits: new stems per segment (fractions carried as an error term).
    pub seg_splits: f32,
    /// nSplitAngle: angle between split stems, degrees.
    pub split_angle: f32,
    /// nSplitAngleV: its variation, degrees.
    pub split_angle_v: f32,
    /// nCurveRes: segments per stem.
    pub curve_res: u32,
    /// nCurve: total curvature along the stem, degrees (negative: downwards).
    pub curve: f32,
    /// nCurveBack: curvature of the second half (S-curves), degrees; 0 for none.
    pub curve_back: f32,
    /// nCurveV: random curvature per segment, degrees; negative makes a helix.
    pub curve_v: f32,
    /// nDownAngle: angle from the parent's axis, degrees (level ≥ 1).
    pub down_angle: f32,
    /// nDownAngleV: its variation, degrees; negative varies along the parent.
    pub down_angle_v: f32,
    /// nRotate: rotation about the parent between successive children, degrees; negative
    /// alternates sides.
    pub rotate: f32,
    /// nRotateV: its variation, degrees.
    pub rotate_v: f32,
    /// nBranches: children per parent stem (level ≥ 1).
    pub branches: f32,
}

/// A Weber–Penn species.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Species {
    /// Name (from the file name or the preset).
    pub name: String,
    /// Shape: crown envelope 0 conical, 1 spherical, 2 hemispherical, 3 cylindrical,
    /// 4 tapered cylindrical, 5 flame, 6 inverse conical, 7 tend flame, 8 envelope (pruning).
    pub shape: u32,
    /// BaseSize: fraction of the trunk without branches.
    pub base_size: f32,
    /// Scale: tree size, m.
    pub scale: f32,
    /// ScaleV: its variation, m.
    pub scale_v: f32,
    /// ZScale, ZScaleV: vertical scaling (kept for completeness; 1 and 0 for trees).
    pub z_scale: f32,
    /// ZScaleV.
    pub z_scale_v: f32,
    /// Levels: recursion depth (1–4).
    pub levels: u32,
    /// Ratio: trunk radius to tree length.
    pub ratio: f32,
    /// RatioPower: how child radii shrink with their length.
    pub ratio_power: f32,
    /// Lobes: sinusoidal lobes of the trunk cross-section.
    pub lobes: u32,
    /// MaxJoints (Sylva): the most joints a tree of this species may grow; generation is
    /// refused beyond it (before growing when the branch counts already exceed it). A guard
    /// against branch counts that would take the machine's memory, raised deliberately.
    pub max_joints: u32,
    /// LobeDepth: their depth relative to the radius.
    pub lobe_depth: f32,
    /// Flare: widening of the trunk base, relative.
    pub flare: f32,
    /// 0Scale, 0ScaleV: trunk radius scale and variation.
    pub scale0: f32,
    /// 0ScaleV.
    pub scale0_v: f32,
    /// 0BaseSplits: splits right above the trunk base.
    pub base_splits: u32,
    /// Leaves: leaves per last-level stem (negative: fan).
    pub leaves: f32,
    /// LeafShape: 0–8, the outline in WP95's list.
    pub leaf_shape: u32,
    /// LeafScale: leaf length, m.
    pub leaf_scale: f32,
    /// LeafScaleX: leaf width relative to its length.
    pub leaf_scale_x: f32,
    /// AttractionUp: how strongly stems bend towards (or away from, < 0) the light.
    pub attraction_up: f32,
    /// PruneRatio: 0 off, 1 full pruning to the envelope.
    pub prune_ratio: f32,
    /// PruneWidth: envelope width relative to height.
    pub prune_width: f32,
    /// PruneWidthPeak: relative height of the envelope's widest point.
    pub prune_width_peak: f32,
    /// PrunePowerLow: curvature of the envelope's lower part.
    pub prune_power_low: f32,
    /// PrunePowerHigh: curvature of its upper part.
    pub prune_power_high: f32,
    /// LeafQuality: fraction of leaves kept (they grow to keep the area).
    pub leaf_quality: f32,
    /// BarkShade (Sylva): bark colour, 0 dark brown … 1 pale (aspen).
    pub bark_shade: f32,
    /// BarkRoughness (Sylva): 0 smooth … 1 deeply furrowed.
    pub bark_roughness: f32,
    /// LeafShade (Sylva): foliage colour, 0 dark blue-green … 1 light yellow-green.
    pub leaf_shade: f32,
    /// Per-level parameters, levels 0–3.
    pub level: [LevelParams; 4],
}

/// Mutable storage of one parameter.
enum Slot<'a> {
    F(&'a mut f32),
    U(&'a mut u32),
}

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

const fn g(
    name: &'static str,
    unit: &'static str,
    min: f32,
    max: f32,
    integer: bool,
    default: f32,
    doc: &'static str,
) -> ParamDoc {
    ParamDoc { name, scope: Scope::Global, unit, min, max, integer, default, doc }
}
const fn l(
    name: &'static str,
    unit: &'static str,
    min: f32,
    max: f32,
    integer: bool,
    default: f32,
    doc: &'static str,
) -> ParamDoc {
    ParamDoc { name, scope: Scope::Level, unit, min, max, integer, default, doc }
}

/// Every parameter of a species file.
pub const PARAMS: &[ParamDoc] = &[
    g(
        "Shape",
        "",
        0.0,
        8.0,
        true,
        4.0,
        "crown envelope: 0 conical, 1 spherical, 2 hemispherical, 3 cylindrical, 4 tapered cylindrical, 5 flame, 6 inverse conical, 7 tend flame, 8 pruning envelope",
    ),
    g("BaseSize", "", 0.0, 1.0, false, 0.25, "fraction of the trunk below the first branch"),
    g("Scale", "m", 0.1, 150.0, false, 10.0, "tree size"),
    g("ScaleV", "m", 0.0, 100.0, false, 0.0, "variation of Scale"),
    g("ZScale", "", 0.0, 10.0, false, 1.0, "vertical scaling"),
    g("ZScaleV", "", 0.0, 10.0, false, 0.0, "variation of ZScale"),
    g("Levels", "", 1.0, 4.0, true, 3.0, "recursion depth: trunk, branches, sub-branches, twigs"),
    g(
        "MaxJoints",
        "joints",
        1000.0,
        16_000_000.0,
        true,
        1_000_000.0,
        "guard: the most joints a tree may grow (about 1 kB of memory each with its mesh); \
         the weeping willow grows 80 000",
    ),
    g("Ratio", "", 0.001, 0.5, false, 0.015, "trunk base radius divided by tree length"),
    g(
        "RatioPower",
        "",
        0.0,
        5.0,
        false,
        1.2,
        "child radius = parent radius × (child length / parent length)^RatioPower",
    ),
    g("Lobes", "", 0.0, 20.0, true, 0.0, "lobes of the trunk cross-section"),
    g("LobeDepth", "", 0.0, 1.0, false, 0.0, "depth of the lobes, relative to the radius"),
    g("Flare", "", 0.0, 10.0, false, 0.5, "widening of the trunk base, relative to its radius"),
    g("0Scale", "", 0.01, 10.0, false, 1.0, "trunk radius scale"),
    g("0ScaleV", "", 0.0, 10.0, false, 0.0, "variation of 0Scale"),
    g("0BaseSplits", "", 0.0, 10.0, true, 0.0, "clones made at the trunk base (one split level)"),
    g(
        "Leaves",
        "per stem",
        -20000.0,
        20000.0,
        false,
        20.0,
        "leaves on each last-level stem (negative: fan at the tip)",
    ),
    g(
        "LeafShape",
        "",
        0.0,
        8.0,
        true,
        0.0,
        "leaf outline: 0 elliptic, 1 lanceolate, 2 ovate, 3 rounded with a pointed tip, 4 lobed, 5 palmate, 6 needle, 7 round, 8 heart",
    ),
    g("LeafScale", "m", 0.001, 5.0, false, 0.15, "leaf length"),
    g("LeafScaleX", "", 0.01, 5.0, false, 0.7, "leaf width / length"),
    g(
        "AttractionUp",
        "",
        -10.0,
        10.0,
        false,
        0.0,
        "bend of stems towards the sky (negative: droop)",
    ),
    g("PruneRatio", "", 0.0, 1.0, false, 0.0, "0 no pruning, 1 stems cut to the envelope"),
    g("PruneWidth", "", 0.01, 10.0, false, 0.5, "envelope width relative to the tree height"),
    g("PruneWidthPeak", "", 0.0, 1.0, false, 0.5, "relative height of the envelope's widest point"),
    g("PrunePowerLow", "", 0.0, 10.0, false, 0.5, "curvature of the envelope below its peak"),
    g("PrunePowerHigh", "", 0.0, 10.0, false, 0.5, "curvature of the envelope above its peak"),
    g(
        "LeafQuality",
        "",
        0.01,
        1.0,
        false,
        1.0,
        "fraction of leaves generated (the rest enlarge to keep the area)",
    ),
    g("BarkShade", "", 0.0, 1.0, false, 0.3, "bark colour: 0 dark brown … 1 pale (Sylva)"),
    g("BarkRoughness", "", 0.0, 1.0, false, 0.6, "bark: 0 smooth … 1 deep furrows (Sylva)"),
    g(
        "LeafShade",
        "",
        0.0,
        1.0,
        false,
        0.5,
        "foliage: 0 dark blue-green … 1 light yellow-green (Sylva)",
    ),
    l(
        "Length",
        "",
        0.0,
        10.0,
        false,
        0.5,
        "stem length relative to the parent (level 0: to the tree size)",
    ),
    l("LengthV", "", 0.0, 10.0, false, 0.0, "variation of Length"),
    l("Taper", "", 0.0, 3.0, false, 1.0, "0 cylinder, 1 cone, 1–2 rounded tip, 2–3 periodic"),
    l(
        "SegSplits",
        "per segment",
        0.0,
        2.0,
        false,
        0.0,
        "splits per segment, fractions carried forward as an error term",
    ),
    l("SplitAngle", "°", 0.0, 180.0, false, 0.0, "angle between split stems"),
    l("SplitAngleV", "°", 0.0, 180.0, false, 0.0, "variation of SplitAngle"),
    l("CurveRes", "segments", 1.0, 64.0, true, 3.0, "segments per stem"),
    l("Curve", "°", -360.0, 360.0, false, 0.0, "total curvature along the stem"),
    l(
        "CurveBack",
        "°",
        -360.0,
        360.0,
        false,
        0.0,
        "curvature of the upper half (S-curve); 0 for none",
    ),
    l("CurveV", "°", -720.0, 720.0, false, 0.0, "random curvature per stem; negative: helix"),
    l("DownAngle", "°", -180.0, 180.0, false, 45.0, "angle between a child and its parent's axis"),
    l(
        "DownAngleV",
        "°",
        -180.0,
        180.0,
        false,
        0.0,
        "variation of DownAngle (negative: varies along the parent)",
    ),
    l(
        "Rotate",
        "°",
        -360.0,
        360.0,
        false,
        140.0,
        "rotation between successive children (negative: alternating)",
    ),
    l("RotateV", "°", 0.0, 360.0, false, 0.0, "variation of Rotate"),
    l("Branches", "per stem", 0.0, 2000.0, false, 0.0, "children per parent stem"),
];

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
    #[error("{file}: line {line}: {message}")]
    Syntax {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
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

fn line_of(text: &str, key: &str) -> usize {
    text.lines()
        .position(|l| {
            let t = l.trim_start();
            let t = t.strip_prefix('"').unwrap_or(t);
            t.strip_prefix(key).is_some_and(|r| {
                let r = r.strip_prefix('"').unwrap_or(r).trim_start();
                r.starts_with('=')
            })
        })
        .map_or(0, |i| i + 1)
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
        // Every field is a parameter of `PARAMS`, whose defaults fill it (a test checks
        // that each field is reached): adding a parameter takes its field, its `PARAMS`
        // entry and its name in `slot`.
        let mut s = Species { name: name.into(), ..Species::default() };
        for p in PARAMS {
            match p.scope {
                Scope::Global => s.set(None, p.name, p.default),
                Scope::Level => (0..4).for_each(|n| s.set(Some(n), p.name, p.default)),
            }
        }
        s
    }

    /// The storage of a parameter, by WP95 name (per-level names without the digit).
    fn slot(&mut self, level: Option<usize>, name: &str) -> Option<Slot<'_>> {
        use Slot::{F, U};
        if let Some(n) = level {
            let lp = self.level.get_mut(n)?;
            return Some(match name {
                "Length" => F(&mut lp.length),
                "LengthV" => F(&mut lp.length_v),
                "Taper" => F(&mut lp.taper),
                "SegSplits" => F(&mut lp.seg_splits),
                "SplitAngle" => F(&mut lp.split_angle),
                "SplitAngleV" => F(&mut lp.split_angle_v),
                "CurveRes" => U(&mut lp.curve_res),
                "Curve" => F(&mut lp.curve),
                "CurveBack" => F(&mut lp.curve_back),
                "CurveV" => F(&mut lp.curve_v),
                "DownAngle" => F(&mut lp.down_angle),
                "DownAngleV" => F(&mut lp.down_angle_v),
                "Rotate" => F(&mut lp.rotate),
                "RotateV" => F(&mut lp.rotate_v),
                "Branches" => F(&mut lp.branches),
                _ => return None,
            });
        }
        Some(match name {
            "Shape" => U(&mut self.shape),
            "BaseSize" => F(&mut self.base_size),
            "Scale" => F(&mut self.scale),
            "ScaleV" => F(&mut self.scale_v),
            "ZScale" => F(&mut self.z_scale),
            "ZScaleV" => F(&mut self.z_scale_v),
            "Levels" => U(&mut self.levels),
            "Ratio" => F(&mut self.ratio),
            "RatioPower" => F(&mut self.ratio_power),
            "Lobes" => U(&mut self.lobes),
            "MaxJoints" => U(&mut self.max_joints),
            "LobeDepth" => F(&mut self.lobe_depth),
            "Flare" => F(&mut self.flare),
            "0Scale" => F(&mut self.scale0),
            "0ScaleV" => F(&mut self.scale0_v),
            "0BaseSplits" => U(&mut self.base_splits),
            "Leaves" => F(&mut self.leaves),
            "LeafShape" => U(&mut self.leaf_shape),
            "LeafScale" => F(&mut self.leaf_scale),
            "LeafScaleX" => F(&mut self.leaf_scale_x),
            "AttractionUp" => F(&mut self.attraction_up),
            "PruneRatio" => F(&mut self.prune_ratio),
            "PruneWidth" => F(&mut self.prune_width),
            "PruneWidthPeak" => F(&mut self.prune_width_peak),
            "PrunePowerLow" => F(&mut self.prune_power_low),
            "PrunePowerHigh" => F(&mut self.prune_power_high),
            "LeafQuality" => F(&mut self.leaf_quality),
            "BarkShade" => F(&mut self.bark_shade),
            "BarkRoughness" => F(&mut self.bark_roughness),
            "LeafShade" => F(&mut self.leaf_shade),
            _ => return None,
        })
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
            let line =
                e.span().map_or(0, |s| text[..s.start.min(text.len())].lines().count().max(1));
            SpeciesError::Syntax { file: file.into(), line, message: e.message().to_string() }
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

    /// `PARAMS` and `slot` reach every numeric field: setting every parameter (on every
    /// level) to 1 leaves no field at its zero default, so `defaults` fills them all.
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
