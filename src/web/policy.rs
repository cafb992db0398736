//! The security headers of every answer, and the Content-Security-Policy of the pages:
//! only the pages' own scripts and styles run, named by their SHA-256 (every inline
//! `<script>` and `<style>` of a page is one of the constants hashed here, and no page
//! has an inline event handler or `style` attribute); nothing is loaded from elsewhere;
//! scripts talk only to this server; no other site may frame a page.

use base64::Engine;
use sha2::{Digest, Sha256};

/// The texts of every inline script of the pages.
pub fn inline_scripts() -> [&'static str; 7] {
    [
        super::pages::PROGRESS_JS,
        super::pages::account::SUBMIT_FORM_JS,
        super::pages::MY_SUBMISSIONS_JS,
        super::pages::MATCH_STDERR_JS,
        super::pages::OWNER_LOGS_JS,
        super::viewer::VIEWER_JS,
        super::finale::FINALE_JS,
    ]
}

/// The texts of every inline style of the pages.
pub fn inline_styles() -> [&'static str; 4] {
    [
        super::layout::SITE_CSS,
        super::viewer::VIEWER_CSS,
        crate::engine::render::SVG_STYLE,
        super::finale::FINALE_CSS,
    ]
}

/// `'sha256-…'`, as a policy names an inline element's text.
pub fn source_hash(text: &str) -> String {
    let digest = Sha256::digest(text.as_bytes());
    format!(
        "'sha256-{}'",
        base64::engine::general_purpose::STANDARD.encode(digest)
    )
}

/// The Content-Security-Policy of every answer.
pub fn content_security_policy() -> String {
    let scripts: Vec<String> = inline_scripts().iter().map(|s| source_hash(s)).collect();
    let styles: Vec<String> = inline_styles().iter().map(|s| source_hash(s)).collect();
    format!(
        "default-src 'none'; script-src {}; style-src {}; img-src 'self' data:; \
         connect-src 'self'; form-action 'self'; base-uri 'none'; frame-ancestors 'none'",
        scripts.join(" "),
        styles.join(" ")
    )
}

/// Every security header: name and value.
pub fn headers() -> Vec<(&'static str, String)> {
    vec![
        ("content-security-policy", content_security_policy()),
        ("x-content-type-options", "nosniff".into()),
        ("x-frame-options", "DENY".into()),
        ("referrer-policy", "no-referrer".into()),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_policy_names_each_inline_text_by_its_hash_and_forbids_framing() {
        let csp = content_security_policy();
        for text in inline_scripts().iter().chain(inline_styles().iter()) {
            assert!(csp.contains(&source_hash(text)));
        }
        assert!(csp.contains("frame-ancestors 'none'"));
        assert!(!csp.contains("unsafe-inline"));
        // A known value: sha256 of "" is 47DEQpj8HBSa+/TImW+5JCeuQeRkm5NMpJWZG3hSuFU=.
        assert_eq!(
            source_hash(""),
            "'sha256-47DEQpj8HBSa+/TImW+5JCeuQeRkm5NMpJWZG3hSuFU='"
        );
    }
}
