//! Compiles the Embree shim and generates its bindings, only with the `embree`
//! feature: a default build needs neither a C toolchain nor libclang.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "embree")]
    embree::build();
}

#[cfg(feature = "embree")]
mod embree {
    use std::env;
    use std::path::{Path, PathBuf};

    const PACKAGE_HINT: &str =
        "on Debian/Ubuntu install them with `apt-get install libembree-dev libclang-dev`";

    /// Where Embree was found, and which major version its headers are.
    struct Embree {
        include_dir: Option<PathBuf>,
        lib_dirs: Vec<PathBuf>,
        major: u32,
    }

    pub fn build() {
        for var in ["EMBREE_INCLUDE_DIR", "EMBREE_LIB_DIR", "LIBCLANG_PATH"] {
            println!("cargo:rerun-if-env-changed={var}");
        }
        println!("cargo:rerun-if-changed=embree-shim/shim.h");
        println!("cargo:rerun-if-changed=embree-shim/shim.c");
        let embree = locate().unwrap_or_else(|msg| fail(&msg));
        compile_shim(&embree);
        link(&embree);
        generate_bindings();
    }

    fn fail(msg: &str) -> ! {
        panic!("{msg}");
    }

    fn locate() -> Result<Embree, String> {
        if let Ok(dir) = env::var("EMBREE_INCLUDE_DIR") {
            let dir = PathBuf::from(dir);
            let major = header_major(&dir).ok_or_else(|| {
                format!(
                    "EMBREE_INCLUDE_DIR={} holds neither embree4/rtcore.h nor embree3/rtcore.h \
                     (unset it to search /usr/include); {PACKAGE_HINT}",
                    dir.display()
                )
            })?;
            return Ok(Embree {
                include_dir: Some(dir),
                lib_dirs: env_lib_dir(),
                major,
            });
        }
        if let Some(found) = from_pkg_config() {
            return Ok(found);
        }
        for dir in ["/usr/include", "/usr/local/include"] {
            if let Some(major) = header_major(Path::new(dir)) {
                return Ok(Embree {
                    include_dir: Some(PathBuf::from(dir)),
                    lib_dirs: env_lib_dir(),
                    major,
                });
            }
        }
        Err(format!(
            "the `embree` feature needs Embree 3 or 4 headers (embree4/rtcore.h or \
             embree3/rtcore.h) and libclang for bindgen; none found in /usr/include or \
             /usr/local/include (set EMBREE_INCLUDE_DIR / EMBREE_LIB_DIR to point elsewhere); \
             {PACKAGE_HINT}"
        ))
    }

    fn header_major(dir: &Path) -> Option<u32> {
        [4, 3]
            .into_iter()
            .find(|m| dir.join(format!("embree{m}/rtcore.h")).is_file())
    }

    fn env_lib_dir() -> Vec<PathBuf> {
        env::var("EMBREE_LIB_DIR")
            .map(|d| vec![PathBuf::from(d)])
            .unwrap_or_default()
    }

    /// pkg-config, when the distribution ships a .pc file (Debian 12 does not).
    fn from_pkg_config() -> Option<Embree> {
        for major in [4, 3] {
            let name = format!("embree{major}");
            let Some(cflags) = pkg_config(&["--cflags-only-I", &name]) else {
                continue;
            };
            let libs = pkg_config(&["--libs-only-L", &name]).unwrap_or_default();
            let strip = |s: &str, p: &str| -> Vec<PathBuf> {
                s.split_whitespace()
                    .filter_map(|w| w.strip_prefix(p).map(PathBuf::from))
                    .collect()
            };
            let include_dir = strip(&cflags, "-I")
                .into_iter()
                .find(|d| header_major(d) == Some(major));
            return Some(Embree {
                include_dir,
                lib_dirs: strip(&libs, "-L"),
                major,
            });
        }
        None
    }

    fn pkg_config(args: &[&str]) -> Option<String> {
        let out = std::process::Command::new("pkg-config")
            .args(args)
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
    }

    fn compile_shim(embree: &Embree) {
        let mut build = cc::Build::new();
        build
            .file("embree-shim/shim.c")
            .std("c11")
            .define("EMBER_EMBREE_MAJOR", embree.major.to_string().as_str())
            .warnings(true);
        if let Some(dir) = &embree.include_dir {
            build.include(dir);
        }
        build.compile("ember_embree_shim");
    }

    fn link(embree: &Embree) {
        for dir in &embree.lib_dirs {
            println!("cargo:rustc-link-search=native={}", dir.display());
        }
        println!("cargo:rustc-link-lib=dylib=embree{}", embree.major);
    }

    fn generate_bindings() {
        // bindgen panics when it cannot load libclang; turn that into the package hint.
        let loaded = std::panic::catch_unwind(bindgen::clang_version);
        if loaded.is_err() {
            fail(&format!(
                "bindgen could not load libclang (set LIBCLANG_PATH if it is installed \
                 elsewhere); {PACKAGE_HINT}"
            ));
        }
        let bindings = bindgen::Builder::default()
            .header("embree-shim/shim.h")
            .allowlist_function("ember_.*")
            .allowlist_type("ember_.*")
            .allowlist_var("EMBER_.*")
            .layout_tests(false)
            .generate()
            .unwrap_or_else(|e| {
                fail(&format!(
                    "bindgen failed on embree-shim/shim.h: {e} (a missing 'stddef.h' means \
                     clang's own headers are absent); {PACKAGE_HINT}"
                ))
            });
        let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
        bindings
            .write_to_file(out.join("embree_shim.rs"))
            .unwrap_or_else(|e| fail(&format!("cannot write bindings: {e}")));
    }
}
