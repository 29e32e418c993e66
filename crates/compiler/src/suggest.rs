//! "Did you mean" suggestions for misspelt names.

/// The candidate closest to `word` by normalized Levenshtein similarity, if close enough to be
/// a plausible typo (similarity ≥ 0.6).
pub fn closest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (strsim::normalized_levenshtein(word, c), c))
        .filter(|(score, _)| *score >= 0.6)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c)
}

/// `help` prefixed with `did you mean "<prefix><closest>"? ` when one of `candidates` is a
/// plausible typo of `word`; the help every "unknown name" diagnostic gives.
pub fn guess_then<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>, prefix: &str, help: String) -> String {
    match closest(word, candidates) {
        Some(best) => format!("did you mean \"{prefix}{best}\"? {help}"),
        None => help,
    }
}

/// `"a", "b" or "c"`.
pub fn quoted_list<S: AsRef<str>>(items: &[S]) -> String {
    let quoted: Vec<String> = items.iter().map(|s| format!("\"{}\"", s.as_ref())).collect();
    match quoted.len() {
        0 => "(none)".to_string(),
        1 => quoted[0].clone(),
        n => format!("{} or {}", quoted[..n - 1].join(", "), quoted[n - 1]),
    }
}

/// `"a", "b", "c"` (a list, not alternatives).
pub fn comma_list<S: AsRef<str>>(items: &[S]) -> String {
    if items.is_empty() {
        return "none".to_string();
    }
    items.iter().map(|s| format!("\"{}\"", s.as_ref())).collect::<Vec<_>>().join(", ")
}
