//! Build script of the core: links the firmware example (`examples/embed.rs`) when it is built
//! for a bare-metal target, with cortex-m-rt's `link.x` and the workspace's `memory.x` (the
//! board's memory map). Nothing else is affected: the library and every host build get no
//! flags.

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let bare_metal = env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "none");
    let Some(manifest) = env::var_os("CARGO_MANIFEST_DIR") else { return };
    let root = PathBuf::from(manifest).join("..");
    println!("cargo:rerun-if-changed={}", root.join("memory.x").display());
    if bare_metal {
        // `link.x` (from cortex-m-rt's own build script) includes `memory.x` from the search path.
        println!("cargo:rustc-link-arg-examples=-L{}", root.display());
        println!("cargo:rustc-link-arg-examples=-Tlink.x");
    }
}
