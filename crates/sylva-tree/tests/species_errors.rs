//! A species file's errors name the line (and, for a syntax error, the column) where the
//! problem is.

use sylva_tree::Species;

fn aspen() -> String {
    Species::load("quaking_aspen").expect("preset").to_toml()
}

#[test]
fn a_stray_table_is_named_at_its_own_line() {
    // It was reported at "line 0".
    let text = format!("{}\n[extra]\nfoo = 1\n", aspen());
    let line = text.lines().position(|l| l == "[extra]").expect("header") + 1;
    let e = Species::from_toml("sp.toml", &text).expect_err("unknown table").to_string();
    assert!(e.contains(&format!("line {line}:")) && e.contains("`extra`"), "{e}");
}

#[test]
fn a_syntax_error_names_its_line_and_column() {
    let text = aspen().replacen("Scale = ", "Scale = = ", 1);
    let (line, l) =
        text.lines().enumerate().find(|(_, l)| l.starts_with("Scale = = ")).expect("Scale");
    let column = l.find("= =").expect("the doubled sign") + 3;
    let e = Species::from_toml("sp.toml", &text).expect_err("syntax").to_string();
    assert!(e.contains(&format!("line {}, column {column}", line + 1)), "{e}");
}
