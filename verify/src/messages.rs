//! Messages that quote user input stay short: an option value, a name or a
//! line of a file is quoted as an [`excerpt`], and [`cut_message`] is the
//! last safety net for anything printed before exiting.

/// Characters of user text quoted in a message.
pub const EXCERPT_CHARS: usize = 100;

/// Longest message printed on exit, in bytes; longer ones keep their head
/// and tail around a note of what was left out.
pub const MAX_MESSAGE_BYTES: usize = 2000;

/// `text` for quoting in a message: at most [`EXCERPT_CHARS`] characters,
/// control characters escaped, and the total length when it is longer
/// ([`exact::quote`]).
pub fn excerpt(text: &str) -> String {
    exact::quote(text, EXCERPT_CHARS)
}

/// `message` if it is at most [`MAX_MESSAGE_BYTES`] long; else its head and
/// tail around a note of how many bytes were omitted ([`exact::cut`]).
pub fn cut_message(message: &str) -> String {
    exact::cut(message, MAX_MESSAGE_BYTES)
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
        // 1 000 024 bytes in all; 2/3 of 2000 (1333) kept at the head and 1/4 (500) at the tail.
        assert!(cut.contains(&format!("[…{} bytes omitted…]", long.len() - 1333 - 500)), "{cut}");
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
