//! With the `embree4` feature: links libembree4.so from the folder `LUXEST_EMBREE4_DIR` names.

fn main() {
    println!("cargo:rerun-if-env-changed=LUXEST_EMBREE4_DIR");
    if std::env::var_os("CARGO_FEATURE_EMBREE4").is_some() {
        if let Some(dir) = std::env::var_os("LUXEST_EMBREE4_DIR") {
            println!("cargo:rustc-link-search=native={}", dir.to_string_lossy());
        }
    }
}
