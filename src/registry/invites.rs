//! A competition's own invite code: set (chosen) or rotated (a fresh random code) by its
//! organiser, removed, and carried by the competition's link. Registering with it makes
//! an entrant whatever the server's registration mode, and leads the new entrant to the
//! competition; its organiser may then give that entrant a new key.
//!
//! Codes are letters, digits, `-`, `_` and `.` (so that a link carries them as they
//! are), 8 to 64 of them; a random one is 14 characters from 31 that cannot be mistaken
//! for each other (about 69 bits), in groups of four.

use super::tokens::hash_token;
use super::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;

/// The shortest and the longest invite code.
pub const CODE_CHARS: std::ops::RangeInclusive<usize> = 8..=64;

/// The characters of a random code: no `0`/`o`, `1`/`l`/`i`.
const ALPHABET: &[u8; 31] = b"abcdefghjkmnpqrstuvwxyz23456789";

/// How many characters a random code has (without its dashes).
const RANDOM_CHARS: usize = 14;

/// Whether `code` may be an invite code: [`CODE_CHARS`] letters, digits, `-`, `_`, `.`.
pub fn valid(code: &str) -> bool {
    CODE_CHARS.contains(&code.len())
        && code
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"-_.".contains(&b))
}

/// A fresh random code, e.g. `k7pq-m2xa-r9tb-vc`.
///
/// # Errors
/// No randomness.
pub fn random() -> Result<String> {
    let mut code = String::new();
    let mut bytes = [0u8; 64];
    let mut chosen = 0;
    while chosen < RANDOM_CHARS {
        getrandom::fill(&mut bytes)
            .map_err(|e| RegistryError::Internal(format!("no randomness: {e}")))?;
        // Rejection sampling: 248 = 8 x 31, so every character is equally likely.
        for b in bytes.iter().filter(|&&b| b < 248) {
            if chosen == RANDOM_CHARS {
                break;
            }
            if chosen > 0 && chosen % 4 == 0 {
                code.push('-');
            }
            code.push(ALPHABET[usize::from(*b) % ALPHABET.len()] as char);
            chosen += 1;
        }
    }
    Ok(code)
}

/// Sets competition `c`'s own invite code to `chosen` (trimmed), or to a fresh random
/// code without one; answers the code. The old code stops working at once.
///
/// # Errors
/// [`RegistryError::Invalid`] for a code that is not [`valid`]; a code another
/// competition has ([`RegistryError::Conflict`]); the database.
pub async fn set(storage: &Storage, c: &CompetitionRow, chosen: Option<&str>) -> Result<String> {
    let code = match chosen.map(str::trim).filter(|s| !s.is_empty()) {
        Some(code) if valid(code) => code.to_string(),
        Some(_) => {
            return Err(RegistryError::Invalid(format!(
                "an invite code is {} to {} letters, digits, '-', '_' or '.'",
                CODE_CHARS.start(),
                CODE_CHARS.end()
            )));
        }
        None => random()?,
    };
    storage
        .set_competition_invite(c.competition_id, Some((&code, &hash_token(&code))))
        .await?;
    Ok(code)
}

/// Removes competition `c`'s own invite code.
///
/// # Errors
/// The database.
pub async fn remove(storage: &Storage, c: &CompetitionRow) -> Result<()> {
    Ok(storage
        .set_competition_invite(c.competition_id, None)
        .await?)
}

/// The competition's link that carries its invite code: its page, whose "How to take
/// part" leads to the registration with the code filled in.
pub fn link(c: &CompetitionRow, code: &str) -> String {
    format!("/competitions/{}?invite={code}#take-part", c.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_codes_are_valid_unambiguous_and_differ() {
        let a = random().unwrap();
        let b = random().unwrap();
        assert_ne!(a, b);
        for code in [&a, &b] {
            assert!(valid(code), "{code}");
            assert_eq!(code.len(), RANDOM_CHARS + 3, "{code}");
            assert!(!code.contains(['0', 'o', '1', 'l', 'i']), "{code}");
        }
    }

    #[test]
    fn a_chosen_code_is_8_to_64_link_safe_characters() {
        assert!(valid("class-of-2026"));
        assert!(!valid("short"));
        assert!(!valid("has space in it"));
        assert!(!valid("a&b=c#d?e"));
        assert!(!valid(&"x".repeat(65)));
    }

    /// Competition `name`, open now on generated mazes of its own (from `seed` on).
    async fn competition(db: &Storage, name: &str, seed: u64) -> CompetitionRow {
        use crate::competition::{Limits, MazeSets, MazeText, Rule, Spec, Timestamp};
        let now = crate::storage::now_ms();
        let maze = |seed| MazeText {
            name: format!("m{seed}"),
            layout: crate::engine::mazefile::numeric::write(
                &crate::engine::generator::generate(12, seed).unwrap(),
            ),
        };
        let spec = Spec {
            name: name.into(),
            title: name.into(),
            description: String::new(),
            rules: String::new(),
            opens_at: Timestamp(now - 1000),
            closes_at: Timestamp(now + 3_600_000),
            freeze_hours: None,
            repeats: 1,
            final_repeats: 1,
            versions_per_day: 5,
            practice_per_day: 5,
            selection: Rule::Latest,
            max_selected: 1,
            reveal_private_mazes: false,
            hold_results: false,
            limits: Limits::default(),
            validation: Default::default(),
            mazes: MazeSets {
                practice: vec![],
                public: vec![maze(seed)],
                private: vec![maze(seed + 1)],
            },
        };
        crate::registry::competitions::create(db, spec, None)
            .await
            .unwrap()
    }

    #[tokio::test]
    async fn a_code_is_set_rotated_and_removed_and_found_by_its_hash() {
        let (db, _d) = crate::storage::test_support::fresh().await;
        let c = competition(&db, "cup", 4242).await;
        let code = set(&db, &c, Some(" class-of-2026 ")).await.unwrap();
        assert_eq!(code, "class-of-2026");
        let found = db
            .competition_by_invite(&hash_token("class-of-2026"))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(found.invite_code.as_deref(), Some("class-of-2026"));
        assert!(matches!(
            set(&db, &c, Some("bad code")).await,
            Err(RegistryError::Invalid(_))
        ));
        let other = competition(&db, "cup2", 4252).await;
        assert!(matches!(
            set(&db, &other, Some("class-of-2026")).await,
            Err(RegistryError::Conflict(_))
        ));
        let rotated = set(&db, &c, None).await.unwrap();
        assert_ne!(rotated, code);
        assert!(
            db.competition_by_invite(&hash_token(&code))
                .await
                .unwrap()
                .is_none(),
            "the old code stops working"
        );
        assert_eq!(
            link(&c, &rotated),
            format!("/competitions/cup?invite={rotated}#take-part")
        );
        remove(&db, &c).await.unwrap();
        assert!(
            db.competition_by_invite(&hash_token(&rotated))
                .await
                .unwrap()
                .is_none()
        );
    }
}
