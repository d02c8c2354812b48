//! Small checks shared by the scene loader, `eval` and the CLI: how to quote
//! user input back in a message, and range checks for numeric fields.

/// `s` cut to at most `max` characters (on a character boundary), with the
/// number of characters left out, so a 5 MB bad value does not come back as
/// 5 MB of error message.
pub fn truncate_echo(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        None => s.to_string(),
        Some((cut, _)) => {
            let left = s[cut..].chars().count();
            format!("{}… ({left} more characters)", &s[..cut])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncate_keeps_short_text_and_cuts_long_text_on_a_char_boundary() {
        assert_eq!(truncate_echo("abc", 3), "abc");
        assert_eq!(truncate_echo("ééééé", 2), "éé… (3 more characters)");
    }
}
