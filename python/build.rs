//! The documentation of every wind-model parameter, read from the doc comments of
//! `sylva-wind`'s `params.rs` at build time, so Python shows the Rust documentation itself
//! (`sylva_wind.PARAMETER_DOCS`) and the two cannot drift apart.
//!
//! Keys, as the parameter dictionaries spell them: `u_star` (a field of `WindParams`),
//! `profile.z0` (a field of a profile kind), `profile.kind=log` (a kind), `spectrum=kaimal`
//! (a value), `spectrum_constants[].a`, `coherence[].cy` (fields of the per-component
//! entries), `coherence_speed=pair-mean`.

use std::fmt::Write as _;

fn kebab(name: &str) -> String {
    let mut out = String::new();
    for (i, ch) in name.chars().enumerate() {
        if ch.is_ascii_uppercase() {
            if i > 0 {
                out.push('-');
            }
            out.push(ch.to_ascii_lowercase());
        } else {
            out.push(ch);
        }
    }
    out
}

/// Rustdoc markup to plain text: intra-doc links `[`X`]` and `[`X`](Y)` become `X`.
fn plain(doc: &str) -> String {
    let mut s = doc.replace("[`", "`").replace("`]", "`");
    while let Some(at) = s.find("`(") {
        let Some(end) = s[at..].find(')') else { break };
        s.replace_range(at + 1..at + end + 1, "");
    }
    s
}

fn main() {
    let source = "../crates/sylva-wind/src/params.rs";
    println!("cargo:rerun-if-changed={source}");
    let text = std::fs::read_to_string(source).expect("sylva-wind's params.rs");
    // The item each key lives under: struct/enum name → (prefix for fields, prefix for
    // variants).
    let item_key = |item: &str| -> Option<(&'static str, &'static str)> {
        Some(match item {
            "WindParams" => ("", ""),
            "Profile" => ("profile.", "profile.kind="),
            "SpectrumModel" => ("", "spectrum="),
            "SpectrumConstants" => ("spectrum_constants[].", ""),
            "CoherenceConstants" => ("coherence[].", ""),
            "CoherenceSpeed" => ("", "coherence_speed="),
            _ => return None,
        })
    };
    let mut docs: Vec<(String, String)> = Vec::new();
    let mut doc = String::new();
    let mut item: Option<(&str, bool)> = None; // (name, is enum)
    for line in text.lines() {
        let t = line.trim();
        if let Some(d) = t.strip_prefix("///") {
            if !doc.is_empty() {
                doc.push(' ');
            }
            doc.push_str(d.trim());
            continue;
        }
        if t.starts_with("#[") {
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        if indent == 0 {
            item = if let Some(rest) = t.strip_prefix("pub struct ") {
                Some((rest.split([' ', '{']).next().unwrap_or(""), false))
            } else if let Some(rest) = t.strip_prefix("pub enum ") {
                Some((rest.split([' ', '{']).next().unwrap_or(""), true))
            } else {
                None
            };
        } else if let Some((name, is_enum)) = item
            && let Some((field_prefix, variant_prefix)) = item_key(name)
            && !doc.is_empty()
        {
            let ident: String = t
                .trim_start_matches("pub ")
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !ident.is_empty() {
                let key = if is_enum && indent == 4 {
                    format!("{variant_prefix}{}", kebab(&ident))
                } else {
                    format!("{field_prefix}{ident}")
                };
                docs.push((key, plain(&doc)));
            }
        }
        doc.clear();
    }
    let mut json = String::from("{");
    for (i, (k, v)) in docs.iter().enumerate() {
        let esc = |s: &str| s.replace('\\', "\\\\").replace('"', "\\\"");
        let _ = write!(json, "{}\"{}\": \"{}\"", if i > 0 { ", " } else { "" }, esc(k), esc(v));
    }
    json.push('}');
    let out = std::env::var("OUT_DIR").expect("OUT_DIR");
    std::fs::write(format!("{out}/param_docs.json"), json).expect("writing param_docs.json");
}
