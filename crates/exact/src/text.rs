//! Quoting input in messages. A value or a name is quoted as a short
//! [`quote`]; a whole message is [`cut`] to its head and tail. Input is
//! data of any size: a 50 MB literal must not come back as 50 MB of stderr.
//! Every crate above this one quotes through these two functions.

/// `text` for quoting: at most `max_chars` characters, followed by
/// `… (N bytes)` when it is longer; control characters are escaped (`\n`,
/// `\u{1b}`), so a quoted value cannot break lines or drive a terminal.
///
/// ```
/// assert_eq!(exact::quote("Pi1", 10), "Pi1");
/// assert_eq!(exact::quote(&"x".repeat(50), 3), "xxx… (50 bytes)");
/// assert_eq!(exact::quote("a\nb", 10), "a\\nb");
/// ```
pub fn quote(text: &str, max_chars: usize) -> String {
    let mut out = String::new();
    let mut taken = 0usize;
    for c in text.chars().take(max_chars) {
        if c.is_control() {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
        taken += c.len_utf8();
    }
    if taken < text.len() {
        out.push_str(&format!("… ({} bytes)", text.len()));
    }
    out
}

/// `text` if it has at most `limit` bytes; else its first `2 limit / 3` and
/// last `limit / 4` bytes (at character boundaries) around a note of how many
/// bytes were left out.
///
/// ```
/// let long = format!("head {} tail", "x".repeat(10_000));
/// let cut = exact::cut(&long, 300);
/// assert!(cut.len() < 400 && cut.starts_with("head ") && cut.ends_with(" tail"));
/// assert!(cut.contains("bytes omitted"));
/// assert_eq!(exact::cut("short", 300), "short");
/// ```
pub fn cut(text: &str, limit: usize) -> String {
    if text.len() <= limit {
        return text.to_string();
    }
    let head = (0..=limit * 2 / 3).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0);
    let tail = (text.len() - limit / 4..=text.len()).find(|&i| text.is_char_boundary(i)).unwrap_or(text.len());
    format!("{} […{} bytes omitted…] {}", &text[..head], tail - head, &text[tail..])
}
