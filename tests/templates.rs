//! The reports' templates: every file is embedded, every one parses, and none holds a number as a
//! literal (measured numbers reach the words by name, from the data).

use magdem::report::template::{environment, TEMPLATES};
use std::path::{Path, PathBuf};

fn template_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            template_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "md") {
            out.push(path);
        }
    }
}

/// Removes `open … close` spans (template tags, code spans, link targets).
fn strip(text: &str, open: &str, close: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find(open) {
        out.push_str(&rest[..start]);
        match rest[start + open.len()..].find(close) {
            Some(end) => rest = &rest[start + open.len() + end + close.len()..],
            None => {
                rest = "";
                break;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The digits a template may hold in its words: names of the paper's tables and cases, the names
/// CI95, 3-D/2-D and "2+" (aggregates of two or more), and the years of citations.
fn allowed(text: &str) -> String {
    let mut t = text.to_string();
    for year in 1900..2100 {
        t = t.replace(&format!("{year})"), ")").replace(&format!(" {year},"), ",").replace(&format!(" {year};"), ";");
    }
    for n in 0..10 {
        for prefix in ["Table ", "table ", "Case ", "case ", "case", "case-", "Case-"] {
            t = t.replace(&format!("{prefix}{n}"), "");
        }
        t = t.replace(&format!("{n}-D"), "");
    }
    t.replace("CI95", "").replace("2+", "")
}

#[test]
fn every_template_file_is_embedded_and_parses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("templates");
    let mut files = vec![];
    template_files(&root, &mut files);
    let mut on_disk: Vec<String> =
        files.iter().map(|f| f.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/")).collect();
    let mut embedded: Vec<String> = TEMPLATES.iter().map(|(name, _)| name.to_string()).collect();
    on_disk.sort();
    embedded.sort();
    assert_eq!(on_disk, embedded, "templates/ and template::TEMPLATES list the same files");
    let env = environment();
    for (name, _) in TEMPLATES {
        env.get_template(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn no_template_holds_a_number_as_a_literal() {
    let mut offenders = vec![];
    for (name, text) in TEMPLATES {
        let words = [("{{", "}}"), ("{%", "%}"), ("{#", "#}"), ("`", "`"), ("](", ")")]
            .iter()
            .fold(text.to_string(), |t, (open, close)| strip(&t, open, close));
        for (k, line) in allowed(&words).lines().enumerate() {
            if line.chars().any(|c| c.is_ascii_digit()) {
                offenders.push(format!("{name}:{}: {}", k + 1, line.trim()));
            }
        }
    }
    assert!(offenders.is_empty(), "numbers written into templates:\n{}", offenders.join("\n"));
}

#[test]
fn the_literal_check_finds_a_number() {
    let text = "The mean is {{ x | f(1) }} µm, against 31 µm in `table3.csv` (Table 3, case 2, CI95, 3-D, 2+).";
    let words = [("{{", "}}"), ("`", "`")].iter().fold(text.to_string(), |t, (o, c)| strip(&t, o, c));
    let left: String = allowed(&words).chars().filter(|c| c.is_ascii_digit()).collect();
    assert_eq!(left, "31");
}

#[test]
fn every_paper_section_has_its_template_and_every_partial_a_section() {
    use magdem::report::paper::SECTIONS;
    let embedded: Vec<&str> = TEMPLATES.iter().map(|(name, _)| *name).collect();
    for s in SECTIONS {
        if let Some(t) = s.template {
            assert!(embedded.contains(&t), "section {} names {t}, which is not embedded", s.name);
        }
    }
    for name in embedded.iter().filter(|n| n.starts_with("paper/sections/")) {
        assert!(SECTIONS.iter().any(|s| s.template == Some(name)), "{name} belongs to no section");
    }
    let mut names: Vec<&str> = SECTIONS.iter().map(|s| s.name).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), SECTIONS.len(), "section names are unique");
}
