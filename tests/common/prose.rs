//! Prose of a rendered report, as the report tests count it.

/// Prose sentences: lines that are neither table rows, images nor headings, split at a full
/// stop, question or exclamation mark followed by a space or the line's end.
pub fn sentences(text: &str) -> Vec<String> {
    let mut out = vec![];
    for line in text.lines().map(str::trim) {
        if line.is_empty() || line.starts_with('|') || line.starts_with("![") || line.starts_with('#') {
            continue;
        }
        let chars: Vec<char> = line.chars().collect();
        let mut current = String::new();
        for (k, &c) in chars.iter().enumerate() {
            current.push(c);
            if matches!(c, '.' | '?' | '!') && chars.get(k + 1).is_none_or(|n| n.is_whitespace()) {
                out.push(std::mem::take(&mut current));
            }
        }
        if !current.trim().is_empty() {
            out.push(current);
        }
    }
    out
}
