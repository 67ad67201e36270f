//! Messages that quote user input stay short: an option value, a name or a
//! line of a file is quoted as an [`excerpt`], and [`cut_message`] is the
//! last safety net for anything printed before exiting.

/// Characters of user text quoted in a message.
pub const EXCERPT_CHARS: usize = 100;

/// Longest message printed on exit, in bytes; longer ones keep their head
/// and tail around a note of what was left out.
pub const MAX_MESSAGE_BYTES: usize = 2000;

/// Bytes kept from the head and the tail of a cut message.
const HEAD_BYTES: usize = 1500;
const TAIL_BYTES: usize = 300;

/// `text` for quoting in a message: at most [`EXCERPT_CHARS`] characters,
/// followed by `…` and the total length when it is longer. Control
/// characters are escaped (`\n`, `\u{1b}`), so a quoted value cannot break
/// lines or drive the terminal.
///
/// `excerpt("Pi1")` is `Pi1`; a 10^6-byte value becomes its first 100
/// characters and `… (1000000 bytes)`.
pub fn excerpt(text: &str) -> String {
    let mut out = String::new();
    let mut taken = 0usize;
    for (count, c) in text.chars().enumerate() {
        if count == EXCERPT_CHARS {
            break;
        }
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

/// `message` if it is at most [`MAX_MESSAGE_BYTES`] long; else its first
/// 1500 and last 300 bytes (at character boundaries) around a note of how
/// many bytes were omitted.
pub fn cut_message(message: &str) -> String {
    if message.len() <= MAX_MESSAGE_BYTES {
        return message.to_string();
    }
    let mut head = HEAD_BYTES;
    while !message.is_char_boundary(head) {
        head -= 1;
    }
    let mut tail = message.len() - TAIL_BYTES;
    while !message.is_char_boundary(tail) {
        tail += 1;
    }
    format!("{} … [{} bytes omitted] … {}", &message[..head], tail - head, &message[tail..])
}

/// `message` with every occurrence of the user's `input` replaced by its
/// [`excerpt`], for messages built by library code that quote the input whole.
pub fn quoting(message: String, input: &str) -> String {
    if input.len() <= EXCERPT_CHARS || !message.contains(input) {
        return message;
    }
    message.replace(input, &excerpt(input))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_text_is_quoted_whole() {
        assert_eq!(excerpt("Pi1"), "Pi1");
        assert_eq!(excerpt(&"a".repeat(EXCERPT_CHARS)), "a".repeat(EXCERPT_CHARS));
    }

    #[test]
    fn long_text_is_cut_with_its_length() {
        let long = "é".repeat(1_000_000); // 2 bytes a character
        let e = excerpt(&long);
        assert_eq!(e, format!("{}… (2000000 bytes)", "é".repeat(EXCERPT_CHARS)));
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(excerpt("a\nb\u{1b}[31m"), "a\\nb\\u{1b}[31m");
    }

    #[test]
    fn messages_are_cut_to_head_and_tail() {
        assert_eq!(cut_message("short"), "short");
        let long = format!("error: {}: expected K/N", "x".repeat(1_000_000));
        let cut = cut_message(&long);
        assert!(cut.len() < MAX_MESSAGE_BYTES + 100, "{}", cut.len());
        assert!(cut.starts_with("error: xxx") && cut.ends_with("xxx: expected K/N"));
        // 1 000 024 bytes in all, 1500 + 300 kept.
        assert!(cut.contains(&format!("[{} bytes omitted]", long.len() - HEAD_BYTES - TAIL_BYTES)), "{cut}");
        // Character boundaries: a multi-byte character is never split.
        let wide = "é".repeat(5000);
        assert!(cut_message(&wide).starts_with("éé"));
    }

    #[test]
    fn library_messages_quote_an_excerpt() {
        let input = "q".repeat(5000);
        let m = quoting(format!("'{input}': expected NAME=START:STOP:COUNT"), &input);
        assert_eq!(m, format!("'{}… (5000 bytes)': expected NAME=START:STOP:COUNT", "q".repeat(EXCERPT_CHARS)));
    }
}
