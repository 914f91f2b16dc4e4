//! Build script: finds Ipopt with pkg-config, links `libipopt` and generates Rust
//! bindings for Ipopt's C interface (`IpStdCInterface.h`) with bindgen.
//!
//! Outputs:
//! * `cargo:rustc-link-lib=ipopt` plus a `rustc-link-search` path for the directory
//!   holding `libipopt`. Only `ipopt` itself is linked: `libipopt.so` already depends
//!   on MUMPS, LAPACK and BLAS, and the `-llapack -lblas` that Debian's `ipopt.pc`
//!   names need development symlinks that are usually not installed.
//! * `cargo:rustc-env=SKG_IPOPT_VERSION=<version reported by pkg-config>`.
//! * `$OUT_DIR/ipopt_bindings.rs`, included by `src/ffi.rs`.

use std::env;
use std::path::{Path, PathBuf};

const INSTALL_HINT: &str = "install it with `sudo apt-get install coinor-libipopt-dev pkg-config libclang-dev` \
     (or run `bash ci/install-deps.sh`), or point PKG_CONFIG_PATH at the directory that holds ipopt.pc";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let library = probe_ipopt();
    emit_link_lines(&library);
    let header = find_header(&library);
    generate_bindings(&header, &clang_args(&library));
}

/// Finds Ipopt with pkg-config, without pkg-config's own link lines.
fn probe_ipopt() -> pkg_config::Library {
    pkg_config::Config::new()
        .cargo_metadata(false) // we emit our own, reduced link line (see above)
        .env_metadata(true) // rerun when PKG_CONFIG_PATH & co. change
        .probe("ipopt")
        .unwrap_or_else(|e| panic!("\n\nskg-solve needs Ipopt, but pkg-config could not find it: {e}\n\n{INSTALL_HINT}\n\n"))
}

/// Links only ipopt, and passes Ipopt's version to the crate. Search path: pkg-config's
/// `libdir` (pkg-config omits system dirs from --libs) plus any -L directory that
/// actually contains libipopt.
fn emit_link_lines(library: &pkg_config::Library) {
    let mut search: Vec<PathBuf> = Vec::new();
    if let Ok(libdir) = pkg_config::get_variable("ipopt", "libdir") {
        if !libdir.is_empty() {
            search.push(PathBuf::from(libdir));
        }
    }
    for dir in &library.link_paths {
        if has_libipopt(dir) && !search.contains(dir) {
            search.push(dir.clone());
        }
    }
    for dir in &search {
        println!("cargo:rustc-link-search=native={}", dir.display());
    }
    println!("cargo:rustc-link-lib=ipopt");
    println!("cargo:rustc-env=SKG_IPOPT_VERSION={}", library.version);
}

/// `IpStdCInterface.h` in one of the include paths pkg-config gives.
fn find_header(library: &pkg_config::Library) -> PathBuf {
    library.include_paths.iter().map(|dir| dir.join("IpStdCInterface.h")).find(|path| path.is_file()).unwrap_or_else(|| {
        panic!(
            "\n\npkg-config found Ipopt {} but IpStdCInterface.h is not in its include paths {:?}; \
                 {INSTALL_HINT}\n\n",
            library.version, library.include_paths
        )
    })
}

/// Clang's arguments from the pkg-config cflags: the include paths and the defines.
fn clang_args(library: &pkg_config::Library) -> Vec<String> {
    let mut clang_args: Vec<String> = library.include_paths.iter().map(|dir| format!("-I{}", dir.display())).collect();
    let mut defines: Vec<_> = library.defines.iter().collect();
    defines.sort();
    for (name, value) in defines {
        match value {
            Some(value) => clang_args.push(format!("-D{name}={value}")),
            None => clang_args.push(format!("-D{name}")),
        }
    }
    clang_args
}

/// Writes `$OUT_DIR/ipopt_bindings.rs`: the functions and types of the C interface the
/// crate uses.
fn generate_bindings(header: &Path, clang_args: &[String]) {
    let bindings = bindgen::Builder::default()
        .header(header.to_string_lossy().into_owned())
        .clang_args(clang_args)
        .allowlist_function("CreateIpoptProblem")
        .allowlist_function("FreeIpoptProblem")
        .allowlist_function("AddIpoptStrOption")
        .allowlist_function("AddIpoptNumOption")
        .allowlist_function("AddIpoptIntOption")
        .allowlist_function("OpenIpoptOutputFile")
        .allowlist_function("SetIpoptProblemScaling")
        .allowlist_function("SetIntermediateCallback")
        .allowlist_function("IpoptSolve")
        .allowlist_type("Eval_F_CB")
        .allowlist_type("Eval_Grad_F_CB")
        .allowlist_type("Eval_G_CB")
        .allowlist_type("Eval_Jac_G_CB")
        .allowlist_type("Eval_H_CB")
        .allowlist_type("Intermediate_CB")
        .allowlist_type("ApplicationReturnStatus")
        .allowlist_type("AlgorithmMode")
        .allowlist_type("IpoptProblem")
        .allowlist_type("UserDataPtr")
        // Enums as transparent newtypes over the C integer: any value Ipopt returns,
        // even one this crate does not know, is a valid Rust value.
        .default_enum_style(bindgen::EnumVariation::NewType { is_bitfield: false, is_global: false })
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .generate()
        .unwrap_or_else(|e| {
            panic!("\n\nbindgen failed on {}: {e}\n(bindgen needs libclang: `sudo apt-get install libclang-dev`)\n\n", header.display())
        });

    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR for build scripts"));
    let out = out_dir.join("ipopt_bindings.rs");
    bindings.write_to_file(&out).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
}

/// Whether `dir` contains a linkable `libipopt` (shared or static).
fn has_libipopt(dir: &Path) -> bool {
    ["libipopt.so", "libipopt.a", "libipopt.dylib"].iter().any(|name| dir.join(name).exists())
}
