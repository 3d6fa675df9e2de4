//! With the `mujoco` feature the extension module loads the MuJoCo library from the folder it
//! was linked against (`MUJOCO_DYNAMIC_LINK_DIR`, which the repository's `.cargo/config.toml`
//! sets to the one `make mujoco` fills), as the core's build.rs does for its binaries: the
//! module then imports without `LD_LIBRARY_PATH`. Without the feature this does nothing.
fn main() {
    println!("cargo:rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if std::env::var_os("CARGO_FEATURE_MUJOCO").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
