//! Tidy checks: the architecture's invariants (ARCHITECTURE.md), read off the workspace's
//! manifests and sources rather than trusted to review.
//!
//! - `naadf-world` depends on no async, network or GPU crate;
//! - the server and the client never depend on each other;
//! - without its `gpu` feature neither the client nor the CLI links the renderer;
//! - the CLI names no wire type;
//! - no crate has a file-level import circle (`tidy/imports.rs` says what counts);
//! - no WGSL `const` copies a Rust item by hand (the shaders get those generated).

#[path = "tidy/imports.rs"]
mod imports;

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The host's target triple, as rustc names it.
fn host() -> String {
    let out = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .arg("-vV")
        .output()
        .expect("rustc runs");
    let text = String::from_utf8(out.stdout).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix("host: "))
        .expect("rustc -vV names the host")
        .to_owned()
}

/// `cargo metadata` of the workspace for this host (so that it needs no package that the
/// build did not fetch), with `flags`.
fn metadata(flags: &[&str]) -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--filter-platform",
            &host(),
        ])
        .args(flags)
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// The resolved dependency graph: package name → the names of its dependencies, of the
/// given kinds (`"normal"`, `"dev"`, `"build"`).
fn dependencies(meta: &Value, kinds: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let name_of: BTreeMap<&str, &str> = meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap(), p["name"].as_str().unwrap()))
        .collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for node in meta["resolve"]["nodes"].as_array().unwrap() {
        let deps = graph
            .entry(name_of[node["id"].as_str().unwrap()].to_owned())
            .or_default();
        for dep in node["deps"].as_array().unwrap() {
            let of_kind = dep["dep_kinds"]
                .as_array()
                .unwrap()
                .iter()
                .any(|k| kinds.contains(&k["kind"].as_str().unwrap_or("normal")));
            if of_kind {
                deps.insert(name_of[dep["pkg"].as_str().unwrap()].to_owned());
            }
        }
    }
    graph
}

/// Every package `package` reaches through `graph`.
fn reach(graph: &BTreeMap<String, BTreeSet<String>>, package: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![package.to_owned()];
    while let Some(p) = todo.pop() {
        for d in graph.get(&p).into_iter().flatten() {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

/// Crates of an async runtime, a network stack or a GPU: `naadf-world` is plain
/// synchronous Rust that every other crate builds on.
const NOT_IN_THE_WORLD: &[&str] = &[
    "tokio",
    "futures",
    "futures-util",
    "async-trait",
    "mio",
    "hyper",
    "h2",
    "http",
    "tower",
    "tonic",
    "prost",
    "axum",
    "rustls",
    "wgpu",
    "wgpu-core",
    "wgpu-hal",
    "naga",
    "ash",
    "winit",
    "naadf-proto",
    "naadf-server",
    "naadf-client",
];

#[test]
fn the_world_depends_on_no_async_network_or_gpu_crate() {
    let graph = dependencies(&metadata(&[]), &["normal"]);
    let found: Vec<String> = reach(&graph, "naadf-world")
        .into_iter()
        .filter(|d| NOT_IN_THE_WORLD.contains(&d.as_str()))
        .collect();
    assert!(found.is_empty(), "naadf-world depends on {found:?}");
}

#[test]
fn server_and_client_never_depend_on_each_other() {
    let graph = dependencies(&metadata(&[]), &["normal", "dev", "build"]);
    for (a, b) in [("naadf-server", "naadf-client"), ("naadf-client", "naadf-server")] {
        assert!(!reach(&graph, a).contains(b), "{a} depends on {b}");
    }
}

/// The renderer's crates, which a program that only serves, relays or mirrors must not link.
const RENDERER: &[&str] = &["wgpu", "winit", "nv-flip"];

#[test]
fn without_the_gpu_feature_nothing_links_the_renderer() {
    let graph = dependencies(&metadata(&["--no-default-features"]), &["normal"]);
    for package in ["naadf-client", "naadf"] {
        let found: Vec<String> = reach(&graph, package)
            .into_iter()
            .filter(|d| RENDERER.contains(&d.as_str()))
            .collect();
        assert!(found.is_empty(), "{package} without `gpu` depends on {found:?}");
    }
    // And with it, it does: the check looks at the right graph.
    let graph = dependencies(&metadata(&[]), &["normal"]);
    assert!(reach(&graph, "naadf").contains("wgpu"));
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// The identifiers in a file's code (comments and doc text are not code).
fn identifiers(path: &Path) -> BTreeSet<String> {
    fn walk(tokens: proc_macro2::TokenStream, out: &mut BTreeSet<String>) {
        for t in tokens {
            match t {
                proc_macro2::TokenTree::Ident(i) => {
                    out.insert(i.to_string());
                }
                proc_macro2::TokenTree::Group(g) => walk(g.stream(), out),
                _ => {}
            }
        }
    }
    let text = std::fs::read_to_string(path).unwrap();
    let tokens: proc_macro2::TokenStream = text.parse().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = BTreeSet::new();
    walk(tokens, &mut out);
    out
}

#[test]
fn the_cli_names_no_wire_type() {
    let graph = dependencies(&metadata(&[]), &["normal"]);
    assert!(
        !graph["naadf"].contains("naadf-proto"),
        "the CLI depends on naadf-proto directly"
    );
    // What the client passes through from the generated wire module.
    let client = std::fs::read_to_string(root().join("client/src/lib.rs")).unwrap();
    let mut wire: BTreeSet<String> = ["naadf_proto", "v1"].map(String::from).into();
    for line in client.lines().filter(|l| l.starts_with("pub use naadf_proto::v1::")) {
        let names = line
            .trim_start_matches("pub use naadf_proto::v1::")
            .trim_end_matches(';');
        wire.extend(names.trim_matches(['{', '}']).split(',').map(|n| n.trim().to_owned()));
    }
    assert!(
        wire.contains("WorldMessage"),
        "the client's re-exports were read: {wire:?}"
    );
    for file in rust_files(&root().join("src")) {
        let named: Vec<String> = identifiers(&file).intersection(&wire).cloned().collect();
        assert!(named.is_empty(), "{} names the wire's {named:?}", file.display());
    }
}

#[test]
fn no_crate_has_a_file_level_import_circle() {
    let mut report = String::new();
    for crate_root in [
        "world/src/lib.rs",
        "proto/src/lib.rs",
        "server/src/lib.rs",
        "client/src/lib.rs",
        "src/main.rs",
    ] {
        let graph = imports::Graph::read(&root().join(crate_root)).unwrap();
        for circle in graph.circles() {
            let files: BTreeSet<&PathBuf> = circle.iter().map(|e| &e.from).collect();
            report.push_str(&format!("circle of {} files in {crate_root}:\n", files.len()));
            for e in &circle {
                let rel = |p: &Path| p.strip_prefix(root()).unwrap_or(p).display().to_string();
                report.push_str(&format!("  {} uses {} from {}\n", rel(&e.from), e.name, rel(&e.to)));
            }
        }
    }
    assert!(report.is_empty(), "file-level import circles:\n{report}");
}

/// A circle of two files the test must see, so that it cannot pass by seeing nothing.
#[test]
fn the_circle_check_sees_a_circle() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("lib.rs", "mod a;\nmod b;\nmod c;\npub use a::A;\n");
    write("a.rs", "use crate::b::B;\npub struct A(B);\n");
    // A re-export alone, and a use inside a test module, are no edges.
    write(
        "b.rs",
        "pub use crate::A as Again;\npub struct B;\nfn f() -> crate::c::C { todo!() }\n#[cfg(test)]\nmod tests { use crate::a::A; }\n",
    );
    write(
        "c.rs",
        "pub struct C;\npub fn g() { let _ = super::a::A(crate::b::B); }\n",
    );
    let graph = imports::Graph::read(&dir.path().join("lib.rs")).unwrap();
    let circles = graph.circles();
    assert_eq!(circles.len(), 1, "{circles:?}");
    let names: BTreeSet<&str> = circles[0].iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["crate::b::B", "crate::c::C", "super::a::A"].into());
}

/// The names declared by a top-level `const` in a WGSL source.
fn wgsl_consts(text: &str) -> BTreeSet<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix("const "))
        .map(|rest| {
            rest.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .next()
                .unwrap()
                .to_owned()
        })
        .collect()
}

/// The names of every `const` and `static` item in the workspace's Rust sources.
fn rust_consts() -> BTreeMap<String, PathBuf> {
    struct Consts<'a>(&'a mut BTreeMap<String, PathBuf>, &'a Path);
    impl<'ast> syn::visit::Visit<'ast> for Consts<'_> {
        fn visit_item_const(&mut self, c: &'ast syn::ItemConst) {
            self.0.insert(c.ident.to_string(), self.1.to_owned());
        }
        fn visit_item_static(&mut self, s: &'ast syn::ItemStatic) {
            self.0.insert(s.ident.to_string(), self.1.to_owned());
        }
        fn visit_impl_item_const(&mut self, c: &'ast syn::ImplItemConst) {
            self.0.insert(c.ident.to_string(), self.1.to_owned());
        }
    }
    let mut out = BTreeMap::new();
    for dir in ["world/src", "proto/src", "server/src", "client/src", "src"] {
        for file in rust_files(&root().join(dir)) {
            let ast = syn::parse_file(&std::fs::read_to_string(&file).unwrap()).unwrap();
            syn::visit::Visit::visit_file(&mut Consts(&mut out, &file), &ast);
        }
    }
    out
}

#[test]
fn no_wgsl_const_copies_a_rust_item() {
    let rust = rust_consts();
    assert!(
        rust.contains_key("STATE_SHIFT") && rust.contains_key("TAA_SLOTS"),
        "the Rust constants were read"
    );
    let mut copies = Vec::new();
    for file in std::fs::read_dir(root().join("shaders")).unwrap() {
        let path = file.unwrap().path();
        if path.extension().is_none_or(|e| e != "wgsl") {
            continue;
        }
        for name in wgsl_consts(&std::fs::read_to_string(&path).unwrap()) {
            if let Some(rust_file) = rust.get(&name) {
                copies.push(format!(
                    "{} declares {name}, which {} defines: generate it from the Rust item",
                    path.display(),
                    rust_file.display()
                ));
            }
        }
    }
    assert!(copies.is_empty(), "{}", copies.join("\n"));
}
