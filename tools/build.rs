//! Lays the code a run executes together at the front of the `regatta` executable.
//!
//! `hot-code.order` (written by `scripts/order-hot-code.sh`) names the functions a run
//! executes; lld places them first, in that order. The kernel maps code in 64 kB blocks
//! around each page a process touches, so gathering them keeps 1.9 MB of code resident in a
//! 1000-robot run instead of 5.7 MB (docs/crowd.md). Only the layout changes: every
//! instruction, and so every result, is the same.
//!
//! The flag is lld's (and mold's), not GNU ld's: it is passed only where Rust links with lld
//! by default (x86_64 Linux, Rust 1.90 and later), no other linker is configured and the
//! user's rustflags pass no link options of their own. `REGATTA_CODE_ORDER=0` turns it off.

use std::path::Path;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=hot-code.order");
    for var in [
        "REGATTA_CODE_ORDER",
        "CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_LINKER",
        "RUSTC_LINKER",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let order = Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("hot-code.order");
    if order.is_file()
        && links_with_default_lld()
        && std::env::var("REGATTA_CODE_ORDER").as_deref() != Ok("0")
    {
        println!(
            "cargo:rustc-link-arg-bin=regatta=-Wl,--symbol-ordering-file={}",
            order.display()
        );
        // A function the file names and this build lacks (renamed since) is passed over.
        println!("cargo:rustc-link-arg-bin=regatta=-Wl,--no-warn-symbol-ordering");
    }
}

/// Whether the executable is linked by the lld Rust uses by default on x86_64 Linux.
fn links_with_default_lld() -> bool {
    let env = |name: &str| std::env::var(name).unwrap_or_default();
    if env("CARGO_CFG_TARGET_ARCH") != "x86_64"
        || env("CARGO_CFG_TARGET_OS") != "linux"
        || env("CARGO_CFG_TARGET_ENV") != "gnu"
        || !env("CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_LINKER").is_empty()
        || !env("RUSTC_LINKER").is_empty()
        || env("CARGO_ENCODED_RUSTFLAGS").contains("link")
    {
        return false;
    }
    // `rustc 1.95.0 (…)`: lld became the default linker of x86_64 Linux in 1.90.
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".to_owned());
    let Ok(output) = Command::new(rustc).arg("--version").output() else {
        return false;
    };
    let version = String::from_utf8_lossy(&output.stdout);
    let mut numbers = version
        .split_whitespace()
        .nth(1)
        .unwrap_or("")
        .split('.')
        .map(|part| part.parse::<u32>().unwrap_or(0));
    let (major, minor) = (numbers.next().unwrap_or(0), numbers.next().unwrap_or(0));
    (major, minor) >= (1, 90)
}
