//! With the `mujoco` feature, binaries (the `pbcs` command, tests, examples) load the MuJoCo
//! library from the folder they were linked against (`MUJOCO_DYNAMIC_LINK_DIR`, which
//! `.cargo/config.toml` sets to the one `make mujoco` fills), so they run without
//! `LD_LIBRARY_PATH`. Without the feature this does nothing.
fn main() {
    println!("cargo:rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if std::env::var_os("CARGO_FEATURE_MUJOCO").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
