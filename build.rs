//! Compiles the Embree shim and generates its bindings, only with the `embree` or
//! `embree4` feature: a default build needs neither a C toolchain nor libclang.
//!
//! `embree` takes Embree 3 or 4 from the system. `embree4` takes Embree 4: headers
//! from the system when present, else the ones the `embree4-sys` crate ships; the
//! library from the system, or from `EMBREE4_LIB_DIR` with an rpath to it.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    git_hash();
    // Both on is refused by a compile_error! in src/accel/embree.rs.
    #[cfg(all(
        any(feature = "embree", feature = "embree4"),
        not(all(feature = "embree", feature = "embree4"))
    ))]
    embree::build();
}

/// `EMBER_GIT_HASH` for the image metadata: the commit being built, with `-dirty` when
/// tracked files differ from it (untracked ones are ignored), or "unknown" outside a
/// git checkout (a crate tarball). Rerun when HEAD moves or a file the binary is made
/// of changes (the sources, the shim, the manifests, and the scripts and scenes it
/// embeds), so the mark follows edits that change the binary without rerunning on
/// every build; an edit elsewhere (docs, tests) shows at the next such rerun.
fn git_hash() {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let hash = match git(&["rev-parse", "HEAD"]) {
        // No optional locks: a build must not hold the index lock a user's git wants.
        Some(hash) => match git(&[
            "--no-optional-locks",
            "status",
            "--porcelain",
            "--untracked-files=no",
        ]) {
            Some(changes) if !changes.is_empty() => format!("{hash}-dirty"),
            _ => hash,
        },
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=EMBER_GIT_HASH={hash}");
    // HEAD, and the branch it names (not all of refs/heads: other worktrees' commits
    // would rerun this); a packed ref has no file of its own, packed-refs holds it.
    let git_path = |p: &str| git(&["rev-parse", "--git-path", p]);
    let branch = git(&["symbolic-ref", "-q", "HEAD"]).and_then(|r| git_path(&r));
    let branch = match branch {
        Some(file) if std::path::Path::new(&file).exists() => Some(file),
        Some(_) => git_path("packed-refs"),
        None => None,
    };
    for file in git_path("HEAD").into_iter().chain(branch) {
        println!("cargo:rerun-if-changed={file}");
    }
    for input in [
        "src",
        "embree-shim",
        "Cargo.toml",
        "Cargo.lock",
        "scripts",
        "scenes",
    ] {
        println!("cargo:rerun-if-changed={input}");
    }
}

#[cfg(all(
    any(feature = "embree", feature = "embree4"),
    not(all(feature = "embree", feature = "embree4"))
))]
mod embree {
    use std::env;
    use std::path::{Path, PathBuf};
    use std::process::Command;

    #[cfg(feature = "embree")]
    const PACKAGE_HINT: &str =
        "on Debian/Ubuntu install them with `apt-get install libembree-dev libclang-dev`";
    #[cfg(feature = "embree4")]
    const PACKAGE_HINT: &str = "on Debian 13 / Ubuntu 24.04 install `libembree-dev \
         libclang-dev`; elsewhere run `scripts/install-deps --embree4` and set \
         EMBREE4_LIB_DIR to the folder it prints";

    /// Where Embree was found, and which major version its headers are.
    struct Embree {
        include_dir: Option<PathBuf>,
        lib_dirs: Vec<PathBuf>,
        /// The library file when its name is not `libembree<major>.so` (the wheel's
        /// hashed names): linked verbatim.
        lib_file: Option<String>,
        /// Embed an rpath to `lib_dirs`, for libraries outside the loader's paths.
        rpath: bool,
        major: u32,
    }

    pub fn build() {
        for var in [
            "EMBREE_INCLUDE_DIR",
            "EMBREE_LIB_DIR",
            "EMBREE4_LIB_DIR",
            "LIBCLANG_PATH",
        ] {
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

    #[cfg(feature = "embree")]
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
            return Ok(system(Some(dir), env_dirs("EMBREE_LIB_DIR"), major));
        }
        if let Some(found) = from_pkg_config(&[4, 3]) {
            return Ok(found);
        }
        if let Some((dir, major)) = standard_headers(&[4, 3]) {
            return Ok(system(Some(dir), env_dirs("EMBREE_LIB_DIR"), major));
        }
        Err(format!(
            "the `embree` feature needs Embree 3 or 4 headers (embree4/rtcore.h or \
             embree3/rtcore.h) and libclang for bindgen; none found in /usr/include or \
             /usr/local/include (set EMBREE_INCLUDE_DIR / EMBREE_LIB_DIR to point elsewhere); \
             {PACKAGE_HINT}"
        ))
    }

    #[cfg(feature = "embree4")]
    fn locate() -> Result<Embree, String> {
        let include_dir = match from_pkg_config(&[4]).and_then(|e| e.include_dir) {
            Some(dir) => dir,
            None => match standard_headers(&[4]) {
                Some((dir, _)) => dir,
                None => embree4_sys_headers()?,
            },
        };
        let Some(dir) = env_dirs("EMBREE4_LIB_DIR").pop() else {
            return system_embree4(include_dir);
        };
        // Absolute, for the rpath; a relative one is taken from the project root.
        let dir = std::fs::canonicalize(&dir)
            .map_err(|e| format!("EMBREE4_LIB_DIR={}: {e}", dir.display()))?;
        let lib_file = lib_in(&dir)?;
        Ok(Embree {
            include_dir: Some(include_dir),
            lib_dirs: vec![dir],
            lib_file,
            rpath: true,
            major: 4,
        })
    }

    /// The system's libembree4.so, where the loader finds it without help.
    #[cfg(feature = "embree4")]
    fn system_embree4(include_dir: PathBuf) -> Result<Embree, String> {
        let pc = from_pkg_config(&[4])
            .map(|e| e.lib_dirs)
            .unwrap_or_default();
        let standard = [
            "/usr/lib/x86_64-linux-gnu",
            "/usr/lib64",
            "/usr/lib",
            "/usr/local/lib",
        ];
        let found = pc
            .iter()
            .map(PathBuf::as_path)
            .chain(standard.iter().map(Path::new))
            .any(|d| d.join("libembree4.so").exists());
        if !found {
            return Err(format!(
                "the `embree4` feature found no libembree4.so in the system's library \
                 folders and EMBREE4_LIB_DIR is not set; {PACKAGE_HINT}"
            ));
        }
        Ok(system(Some(include_dir), pc, 4))
    }

    /// How to link the Embree 4 library in `dir`: `libembree4.so` by its usual name,
    /// else the one `libembree4*.so*` file there (the wheel's SONAME-named file).
    #[cfg(feature = "embree4")]
    fn lib_in(dir: &Path) -> Result<Option<String>, String> {
        if dir.join("libembree4.so").exists() {
            return Ok(None);
        }
        let entries = std::fs::read_dir(dir)
            .map_err(|e| format!("EMBREE4_LIB_DIR={}: {e}", dir.display()))?;
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| n.starts_with("libembree4") && n.contains(".so"))
            .collect();
        names.sort();
        match names.as_slice() {
            [one] => Ok(Some(one.clone())),
            [] => Err(format!(
                "EMBREE4_LIB_DIR={} holds no libembree4*.so*; {PACKAGE_HINT}",
                dir.display()
            )),
            many => Err(format!(
                "EMBREE4_LIB_DIR={} holds several Embree 4 libraries ({}) and no \
                 libembree4.so to say which one to link",
                dir.display(),
                many.join(", ")
            )),
        }
    }

    /// The headers embree4-sys ships in its source (`lib/embree4/`), found through
    /// `cargo metadata` so vendored or patched copies work too.
    #[cfg(feature = "embree4")]
    fn embree4_sys_headers() -> Result<PathBuf, String> {
        let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
        let out = Command::new(cargo)
            .args([
                "metadata",
                "--format-version",
                "1",
                "--offline",
                "--features",
            ])
            .arg("embree4")
            // Only this target's dependencies: without it, cargo wants every
            // platform's crates (Windows ones too), which an offline machine lacks.
            .arg("--filter-platform")
            .arg(env::var("TARGET").expect("cargo sets it"))
            .arg("--manifest-path")
            .arg(manifest.join("Cargo.toml"))
            .output()
            .map_err(|e| format!("cannot run `cargo metadata` to find embree4-sys: {e}"))?;
        let json = String::from_utf8_lossy(&out.stdout);
        let dir = package_dir(&json, "embree4-sys")
            .map(|d| d.join("lib"))
            .filter(|d| header_major(d) == Some(4))
            .ok_or_else(|| {
                format!(
                    "no Embree 4 headers: none in /usr/include, and `cargo metadata` did not \
                     locate embree4-sys's lib/embree4/rtcore.h ({}); {PACKAGE_HINT}",
                    String::from_utf8_lossy(&out.stderr).trim()
                )
            })?;
        println!(
            "cargo:rerun-if-changed={}",
            dir.join("embree4/rtcore.h").display()
        );
        Ok(dir)
    }

    /// The folder of `name`'s Cargo.toml in `cargo metadata` output. Cargo writes
    /// each package as `{"name":...,"version":...,...,"manifest_path":...}`.
    #[cfg(feature = "embree4")]
    fn package_dir(json: &str, name: &str) -> Option<PathBuf> {
        let start = json.find(&format!("{{\"name\":\"{name}\",\"version\":"))?;
        let key = "\"manifest_path\":\"";
        let rest = &json[start..];
        let path_start = rest.find(key)? + key.len();
        let path_len = rest[path_start..].find('"')?;
        let manifest = PathBuf::from(&rest[path_start..path_start + path_len]);
        manifest.parent().map(Path::to_path_buf)
    }

    fn system(include_dir: Option<PathBuf>, lib_dirs: Vec<PathBuf>, major: u32) -> Embree {
        Embree {
            include_dir,
            lib_dirs,
            lib_file: None,
            rpath: false,
            major,
        }
    }

    fn standard_headers(majors: &[u32]) -> Option<(PathBuf, u32)> {
        ["/usr/include", "/usr/local/include"]
            .into_iter()
            .find_map(|dir| {
                let major = header_major(Path::new(dir)).filter(|m| majors.contains(m))?;
                Some((PathBuf::from(dir), major))
            })
    }

    fn header_major(dir: &Path) -> Option<u32> {
        [4, 3]
            .into_iter()
            .find(|m| dir.join(format!("embree{m}/rtcore.h")).is_file())
    }

    fn env_dirs(var: &str) -> Vec<PathBuf> {
        env::var(var)
            .ok()
            .filter(|d| !d.is_empty())
            .map(|d| vec![PathBuf::from(d)])
            .unwrap_or_default()
    }

    /// pkg-config, when the distribution ships a .pc file (Debian 12 does not).
    fn from_pkg_config(majors: &[u32]) -> Option<Embree> {
        for &major in majors {
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
            return Some(system(include_dir, strip(&libs, "-L"), major));
        }
        None
    }

    fn pkg_config(args: &[&str]) -> Option<String> {
        let out = Command::new("pkg-config").args(args).output().ok()?;
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
            if embree.rpath {
                // Every binary of the package (ember, tests, benches) finds it at run time.
                println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
            }
        }
        match &embree.lib_file {
            Some(file) => println!("cargo:rustc-link-lib=dylib:+verbatim={file}"),
            None => println!("cargo:rustc-link-lib=dylib=embree{}", embree.major),
        }
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
