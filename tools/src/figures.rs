//! What every figure shares: the font plotters draws text with, embedded (a fresh machine
//! may have no system fonts).

use std::sync::Once;

/// Registers the embedded sans-serif font with plotters, once.
pub fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Ubuntu Light, as the `epaint_default_fonts` crate ships it (Ubuntu Font Licence).
        let _ = plotters::style::register_font(
            "sans-serif",
            plotters::style::FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}
