//! The viewer's access token: drawn once per run from the operating system's randomness
//! (never from the simulation's seeded streams, which a log's reader knows), and each
//! request's token compared with it in constant time.

/// Random bytes in a token: 128 bits, as many as a UUID's, written as 32 hexadecimal digits.
const TOKEN_BYTES: usize = 16;

/// A run's token, and whether requests must carry it.
pub struct Access {
    pub token: String,
    /// Listening beyond the loopback: a request without the token is refused.
    pub required: bool,
}

impl Access {
    /// Whether a request that carried `given` (or nothing) may be answered: the right token
    /// always; none only on the loopback; a wrong one never.
    pub fn allows(&self, given: Option<&str>) -> bool {
        match given {
            Some(given) => same(given.as_bytes(), self.token.as_bytes()),
            None => !self.required,
        }
    }
}

pub fn new_token() -> Result<String, getrandom::Error> {
    let mut bytes = [0u8; TOKEN_BYTES];
    getrandom::fill(&mut bytes)?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// `a == b` in time that depends on their lengths only, not on where they first differ: a
/// stranger timing refusals learns nothing of the token digit by digit. (Every token has the
/// same length, so the length is no secret.)
fn same(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let difference = a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y));
    // Kept opaque so the compiler cannot turn the fold back into an early exit.
    std::hint::black_box(difference) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_32_hex_digits_and_differ_run_to_run() {
        let (a, b) = (new_token().unwrap(), new_token().unwrap());
        assert_eq!(a.len(), 32);
        assert!(a
            .bytes()
            .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase()));
        assert_ne!(a, b);
    }

    #[test]
    fn the_right_token_is_allowed_a_wrong_one_never_none_only_on_the_loopback() {
        let token = "0123456789abcdef0123456789abcdef".to_owned();
        for required in [false, true] {
            let access = Access {
                token: token.clone(),
                required,
            };
            assert!(access.allows(Some(&token)));
            assert!(!access.allows(Some("0123456789abcdef0123456789abcdee")));
            assert!(!access.allows(Some("0123456789abcdef")));
            assert!(!access.allows(Some("")));
            assert_eq!(access.allows(None), !required);
        }
    }
}
