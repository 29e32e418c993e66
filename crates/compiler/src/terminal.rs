//! Text from the user's files made safe to print. A graph's names, kinds and ids, a file name
//! or a quoted value may hold control characters: ESC starts a terminal escape sequence (set the
//! window title, clear the screen, recolour everything after), BEL rings, CR overwrites the
//! line, and bidirectional overrides reorder what is shown. Everything volgraph prints passes
//! through [`escape_controls`], which writes them as visible escapes (`\x1b`, `\u{202e}`), so
//! what a user reads is what the file holds.

use std::borrow::Cow;

/// Whether `c` must not reach a terminal raw: C0 and C1 controls and DEL (newline and tab
/// excepted: messages have lines), and the bidirectional embedding, override and isolate marks.
pub fn is_unsafe(c: char) -> bool {
    (c.is_control() && c != '\n' && c != '\t') || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` with every [unsafe](is_unsafe) character written as an escape: `\x1b` below U+0100,
/// `\u{202e}` above.
pub fn escape_controls(text: &str) -> Cow<'_, str> {
    if !text.chars().any(is_unsafe) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if !is_unsafe(c) {
            out.push(c);
        } else if (c as u32) < 0x100 {
            out.push_str(&format!("\\x{:02x}", c as u32));
        } else {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        }
    }
    Cow::Owned(out)
}

/// `text` with every [unsafe](is_unsafe) character replaced by `?`s of the same UTF-8 length,
/// so byte spans into it still point at the same places (the source excerpt of a diagnostic).
/// A CR before LF (a Windows line end) is kept.
pub fn mask_controls(text: &str) -> Cow<'_, str> {
    let mut chars = text.chars().peekable();
    let mut masked = String::new();
    let mut changed = false;
    while let Some(c) = chars.next() {
        if is_unsafe(c) && !(c == '\r' && chars.peek() == Some(&'\n')) {
            masked.push_str(&"?".repeat(c.len_utf8()));
            changed = true;
        } else {
            masked.push(c);
        }
    }
    if changed { Cow::Owned(masked) } else { Cow::Borrowed(text) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_are_written_visibly() {
        assert_eq!(escape_controls("a\u{1b}]0;pwned\u{7}b"), "a\\x1b]0;pwned\\x07b");
        assert_eq!(escape_controls("x\u{9b}2J\r"), "x\\x9b2J\\x0d");
        assert_eq!(escape_controls("\u{202e}txt.exe"), "\\u{202e}txt.exe");
        assert!(matches!(escape_controls("plain\n\tline"), Cow::Borrowed(_)));
    }

    #[test]
    fn masking_keeps_byte_offsets() {
        let text = "a\u{1b}b\u{9b}c";
        let masked = mask_controls(text);
        assert_eq!(masked.len(), text.len());
        assert_eq!(masked, "a?b??c");
        assert!(matches!(mask_controls("a\r\nb\r\n"), Cow::Borrowed(_)), "CRLF line ends stay");
        assert_eq!(mask_controls("a\rb"), "a?b", "a lone CR would overwrite the line");
    }
}
