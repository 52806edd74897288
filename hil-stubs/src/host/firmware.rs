//! Where the firmware image is and how it is built (`cargo build --release` in `hil-stubs/`).

use std::format;
use std::io;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::string::String;
use std::vec::Vec;

use super::FIRMWARE_ENV;
use super::error::{HilError, io_error};
use crate::BoardProfile;

/// Where `cargo build --release` in `hil-stubs/` puts the firmware: `$EVOREC_FIRMWARE_ELF` if
/// set, else `$CARGO_TARGET_DIR` (relative paths taken from the workspace root) or the
/// workspace's `target/`, then `thumbv7em-none-eabihf/release/evorec-firmware`.
pub fn default_firmware_path() -> PathBuf {
    if let Some(p) = std::env::var_os(FIRMWARE_ENV) {
        return PathBuf::from(p);
    }
    elf_in(&profile_target_dir(BoardProfile::M4))
}

/// The target directory the firmware of `profile` is built into: the workspace's (or
/// `$CARGO_TARGET_DIR`, relative paths taken from the workspace root) for the M4, its `m7/`
/// subdirectory for the M7 (the two images differ only in features and memory map).
pub fn profile_target_dir(profile: BoardProfile) -> PathBuf {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => workspace.join(dir), // `join` keeps an absolute `dir` as it is
        None => workspace.join("target"),
    };
    if profile == BoardProfile::M7 { target.join("m7") } else { target }
}

fn elf_in(target_dir: &Path) -> PathBuf {
    target_dir.join("thumbv7em-none-eabihf").join("release").join("evorec-firmware")
}

/// Builds the firmware images of `profile` (`evorec-firmware`, `evorec-timing`, …) with
/// `cargo build --release` in `hil-stubs/` — a no-op when they are up to date — and returns
/// the path of `evorec-firmware`, so tests and tools run the firmware of the checked-out
/// source. For the M4, `$EVOREC_FIRMWARE_ELF` (if set) names a prebuilt image and nothing is
/// built.
///
/// # Errors
/// [`HilError::Io`] when cargo cannot be started or the build fails (with cargo's last lines).
pub fn build_firmware(profile: BoardProfile) -> Result<PathBuf, HilError> {
    if profile == BoardProfile::M4
        && let Some(p) = std::env::var_os(FIRMWARE_ENV)
    {
        return Ok(PathBuf::from(p));
    }
    let target_dir = profile_target_dir(profile);
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(env!("CARGO_MANIFEST_DIR")).args(["build", "--release"]).env("CARGO_TARGET_DIR", &target_dir);
    if profile == BoardProfile::M7 {
        cmd.args(["--features", "m7"]);
    }
    let what = format!("build the {} firmware (`cd hil-stubs && cargo build --release`)", profile.name);
    let out = cmd.output().map_err(io_error(what.clone()))?;
    if !out.status.success() {
        let log = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = log.lines().rev().take(15).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(HilError::Io { what, source: io::Error::other(tail.join(" | ")) });
    }
    Ok(elf_in(&target_dir))
}
