//! Files dropped onto the page, read with the command line's readers
//! ([`SceneSpec::from_toml`], [`Species::from_toml`]), so a bad file gives the page the same
//! named error (file, line, field) that `sylva` prints, and never a dead page.
//!
//! Which reader: a scene file sets its keys in lower case (`trees`, `species`, `name`, …),
//! a species file in Weber & Penn's capitalised names (`Shape`, `Levels`, …). A file with a
//! top-level `trees`, `species` or `name` key, or a `[[species]]` table, is read as a
//! scene; any other as a species.

use sylva_forest::{SceneSpec, SpeciesShare};
use sylva_tree::Species;

/// The most trees a scene grown in the page may have: scene D's 50 000. A page has one
/// thread and at most 4 GB; a million trees would freeze it for minutes and then run out of
/// memory, so such a scene is refused with a named error instead (`sylva view` grows it).
pub const PAGE_MAX_TREES: usize = 50_000;

/// What a dropped file holds.
#[derive(Debug, Clone)]
pub enum Dropped {
    /// A scene file.
    Scene(Box<SceneSpec>),
    /// A species file: the name a scene refers to it by (its file name) and the species.
    Species(String, Box<Species>),
}

/// Whether `text` reads as a scene file rather than a species file (see the module notes).
pub fn looks_like_scene(text: &str) -> bool {
    text.lines().map(str::trim_start).any(|l| {
        let key = l.split(['=', ' ', '\t']).next().unwrap_or("");
        (matches!(key, "trees" | "species" | "name")
            && l[key.len()..].trim_start().starts_with('='))
            || l.starts_with("[[species]]")
    })
}

/// Read the file `file` (its name, for errors and as a species' name) holding `text`.
pub fn read_dropped(file: &str, text: &str) -> Result<Dropped, String> {
    if looks_like_scene(text) {
        let spec = SceneSpec::from_toml(file, text).map_err(|e| e.to_string())?;
        if spec.trees > PAGE_MAX_TREES {
            return Err(format!(
                "{file}: `trees` = {} is more than the page grows ({PAGE_MAX_TREES}); \
                 `sylva view` grows it",
                spec.trees
            ));
        }
        Ok(Dropped::Scene(Box::new(spec)))
    } else {
        Species::from_toml(file, text)
            .map(|s| Dropped::Species(file.to_string(), Box::new(s)))
            .map_err(|e| e.to_string())
    }
}

/// The scene that shows the species `name` (a preset, or a species the page has read) close
/// up: one tree of it on level ground in `wind`, from the seed `tree generate` grows by
/// default.
pub fn close_up(name: &str, wind: &str) -> Result<SceneSpec, String> {
    let mut spec = SceneSpec::builtin("small").map_err(|e| e.to_string())?;
    let source = sylva_forest::WindSource::parse(wind)?;
    spec.name = format!("close-up of {name}");
    spec.trees = 1;
    spec.terrain_amplitude = 0.0;
    spec.species = vec![SpeciesShare { name: name.to_string(), weight: 1.0, seed: Some(1) }];
    spec.set_wind(&source);
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = "name = \"mine\"\ntrees = 3\nspecies = [{ name = \"sugar_maple\" }]\n";

    /// A scene file and a shipped species file are told apart by their keys and read by
    /// their own readers.
    #[test]
    fn a_scene_and_a_species_file_go_to_their_readers() {
        match read_dropped("mine.toml", SCENE) {
            Ok(Dropped::Scene(s)) => assert_eq!((s.name.as_str(), s.trees), ("mine", 3)),
            other => panic!("a scene file read as {other:?}"),
        }
        let (_, aspen) =
            sylva_tree::PRESETS.iter().find(|p| p.0 == "quaking_aspen").expect("the aspen");
        assert!(!looks_like_scene(aspen), "a species file has no lower-case scene keys");
        match read_dropped("aspen.toml", aspen) {
            Ok(Dropped::Species(name, sp)) => {
                assert_eq!(name, "aspen.toml");
                let mut preset = Species::preset("quaking_aspen").expect("shipped");
                preset.name = sp.name.clone();
                assert_eq!(*sp, preset, "the same parameters as the shipped aspen");
            }
            other => panic!("a species file read as {other:?}"),
        }
    }

    /// A bad file gives the command line's error, naming the file and the field or line.
    #[test]
    fn bad_files_give_named_errors() {
        let e = read_dropped("mine.toml", &SCENE.replace("trees = 3", "trees = 0"))
            .expect_err("no trees");
        assert_eq!(
            e,
            SceneSpec::from_toml("mine.toml", &SCENE.replace("trees = 3", "trees = 0"))
                .expect_err("no trees")
                .to_string()
        );
        assert!(e.contains("mine.toml") && e.contains("trees"), "{e}");
        let e = read_dropped("oak.toml", "Shape = 7\nLevels = \"three\"\n").expect_err("a string");
        assert!(e.contains("oak.toml") && e.contains("line 2"), "{e}");
        let e = read_dropped("x.toml", "trees = [\n").expect_err("bad syntax");
        assert!(e.contains("x.toml"), "{e}");
        let big = SCENE.replace("trees = 3", "trees = 1000000");
        let e = read_dropped("big.toml", &big).expect_err("too many for a page");
        assert!(e.contains("big.toml") && e.contains("`trees` = 1000000"), "{e}");
        let e = close_up("aspen", "gale").expect_err("no such wind");
        assert!(e.contains("gale"), "{e}");
    }

    /// The close-up grows one tree of the species asked for, the given one where the page
    /// read it, and a species neither shipped nor given is an error naming it.
    #[test]
    fn the_close_up_grows_one_tree_of_the_species() {
        let spec = close_up("douglas_fir", "breeze").expect("a preset");
        let forest = sylva_forest::Forest::new(&spec).expect("grows");
        assert_eq!((forest.trees(), forest.species.len()), (1, 1));
        let fir_height = forest.species[0].model.tree.stats.height;

        let mut short = Species::preset("douglas_fir").expect("the fir");
        short.scale *= 0.5;
        let spec = close_up("short.toml", "breeze").expect("a given species");
        let given = [("short.toml".to_string(), short)];
        let forest = sylva_forest::Forest::with_species(&spec, &given).expect("grows");
        let h = forest.species[0].model.tree.stats.height;
        assert!(h < 0.75 * fir_height, "half the scale grows a shorter fir: {h} vs {fir_height}");

        let Err(e) = sylva_forest::Forest::new(&spec) else { panic!("a species not given grew") };
        let e = e.to_string();
        assert!(e.contains("short.toml"), "{e}");
    }
}
