//! The file-level import graph of one crate, read from its sources with `syn`, and the
//! circles in it.
//!
//! The rules (ARCHITECTURE.md, "Invariants"):
//! - a file uses a name from another file when a `use` (not a re-export) or an inline path
//!   of two or more segments (`crate::status(..)`, `shaders::source(..)`, `Mode::Albedo`)
//!   resolves to an item that the other file defines;
//! - a name counts as coming from the file that defines it: resolution follows `pub use`
//!   re-exports to the definition;
//! - `mod` lines and re-exports (`pub use`, `pub(crate) use`) are not uses themselves;
//! - `#[cfg(test)]` items and modules are left out.
//!
//! Resolution knows the crate's own modules only; a path that leaves the crate (another
//! crate, the prelude, a generic parameter) is no edge. Paths inside macro calls are found
//! by scanning the tokens for `a::b` sequences.

use proc_macro2::{TokenStream, TokenTree};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use syn::visit::Visit;

/// A module of the crate.
#[derive(Default)]
struct Module {
    /// The file that holds it (inline modules share their parent's).
    file: usize,
    parent: Option<usize>,
    children: BTreeMap<String, usize>,
    /// Names of the items it defines.
    defs: BTreeSet<String>,
    /// Names brought in by `use`, with their paths and whether the `use` re-exports.
    imports: BTreeMap<String, (Vec<String>, bool)>,
    /// Paths of glob imports.
    globs: Vec<Vec<String>>,
    /// Paths used inline (two or more segments), and single names (one segment) that
    /// only a glob import can explain.
    uses: Vec<Vec<String>>,
}

/// Where a path leads.
enum Target {
    /// An item defined in this file.
    Item(usize),
    /// A module (no item yet).
    Module(usize),
}

/// One use of a name across files: `from` uses `name`, which `to` defines.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Edge {
    /// The using file.
    pub from: PathBuf,
    /// The defining file.
    pub to: PathBuf,
    /// The path as written.
    pub name: String,
}

/// A crate's module tree and the uses in it.
pub struct Graph {
    files: Vec<PathBuf>,
    modules: Vec<Module>,
}

/// Whether `attrs` hold `#[cfg(test)]`.
fn is_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg")
            && a.meta
                .require_list()
                .is_ok_and(|l| l.tokens.to_string().trim() == "test")
    })
}

/// The name an item defines in its module's namespace, if any.
fn item_name(item: &syn::Item) -> Option<String> {
    let ident = match item {
        syn::Item::Const(i) => &i.ident,
        syn::Item::Enum(i) => &i.ident,
        syn::Item::Fn(i) => &i.sig.ident,
        syn::Item::Static(i) => &i.ident,
        syn::Item::Struct(i) => &i.ident,
        syn::Item::Trait(i) => &i.ident,
        syn::Item::TraitAlias(i) => &i.ident,
        syn::Item::Type(i) => &i.ident,
        syn::Item::Union(i) => &i.ident,
        syn::Item::Macro(i) => i.ident.as_ref()?,
        _ => return None,
    };
    Some(ident.to_string())
}

/// Flattens a `use` tree into `(name, path)` pairs (`None` for the name of a glob).
fn flatten(tree: &syn::UseTree, prefix: &mut Vec<String>, out: &mut Vec<(Option<String>, Vec<String>)>) {
    match tree {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            flatten(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) if n.ident == "self" => out.push((prefix.last().cloned(), prefix.clone())),
        syn::UseTree::Name(n) => {
            let mut path = prefix.clone();
            path.push(n.ident.to_string());
            out.push((Some(n.ident.to_string()), path));
        }
        syn::UseTree::Rename(r) => {
            let mut path = prefix.clone();
            path.push(r.ident.to_string());
            out.push((Some(r.rename.to_string()), path));
        }
        syn::UseTree::Glob(_) => out.push((None, prefix.clone())),
        syn::UseTree::Group(g) => g.items.iter().for_each(|t| flatten(t, prefix, out)),
    }
}

/// Collects the paths a module's code uses, and the `use` items nested in its functions.
struct Paths<'a> {
    module: &'a mut Module,
}

impl Paths<'_> {
    fn add_use(&mut self, u: &syn::ItemUse) {
        let reexport = !matches!(u.vis, syn::Visibility::Inherited);
        let mut pairs = Vec::new();
        flatten(&u.tree, &mut Vec::new(), &mut pairs);
        for (name, path) in pairs {
            // `use a::b::c` in edition 2018+ starts like any path; `::a` is a crate.
            let path: Vec<String> = path.into_iter().filter(|s| !s.is_empty()).collect();
            match name {
                Some(name) => {
                    self.module.imports.insert(name, (path, reexport));
                }
                None => self.module.globs.push(path),
            }
        }
    }

    /// Scans macro tokens for `a::b` sequences.
    fn scan(&mut self, tokens: TokenStream) {
        let tokens: Vec<TokenTree> = tokens.into_iter().collect();
        let mut i = 0;
        while i < tokens.len() {
            match &tokens[i] {
                TokenTree::Group(g) => self.scan(g.stream()),
                TokenTree::Ident(id) => {
                    let mut path = vec![id.to_string()];
                    let mut j = i + 1;
                    while j + 2 < tokens.len() && is_path_sep(&tokens[j], &tokens[j + 1]) {
                        match &tokens[j + 2] {
                            TokenTree::Ident(next) => path.push(next.to_string()),
                            _ => break,
                        }
                        j += 3;
                    }
                    if path.len() >= 2 {
                        self.module.uses.push(path);
                    }
                    i = j - 1;
                }
                _ => {}
            }
            i += 1;
        }
    }
}

/// Whether two tokens are `::`.
fn is_path_sep(a: &TokenTree, b: &TokenTree) -> bool {
    matches!((a, b), (TokenTree::Punct(x), TokenTree::Punct(y))
        if x.as_char() == ':' && y.as_char() == ':' && x.spacing() == proc_macro2::Spacing::Joint)
}

impl<'ast> Visit<'ast> for Paths<'_> {
    fn visit_item(&mut self, item: &'ast syn::Item) {
        match item {
            // Child modules are modules of their own; test code is left out.
            syn::Item::Mod(_) => {}
            syn::Item::Use(u) if !is_test(&u.attrs) => self.add_use(u),
            syn::Item::Use(_) => {}
            i if item_attrs(i).is_some_and(is_test) => {}
            _ => syn::visit::visit_item(self, item),
        }
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        if !is_test(&f.attrs) {
            syn::visit::visit_impl_item_fn(self, f);
        }
    }

    fn visit_path(&mut self, path: &'ast syn::Path) {
        let segments: Vec<String> = path.segments.iter().map(|s| s.ident.to_string()).collect();
        if path.leading_colon.is_none() {
            self.module.uses.push(segments);
        }
        syn::visit::visit_path(self, path);
    }

    fn visit_macro(&mut self, mac: &'ast syn::Macro) {
        self.visit_path(&mac.path);
        self.scan(mac.tokens.clone());
    }
}

/// An item's attributes.
fn item_attrs(item: &syn::Item) -> Option<&[syn::Attribute]> {
    Some(match item {
        syn::Item::Const(i) => &i.attrs,
        syn::Item::Enum(i) => &i.attrs,
        syn::Item::Fn(i) => &i.attrs,
        syn::Item::Impl(i) => &i.attrs,
        syn::Item::Macro(i) => &i.attrs,
        syn::Item::Static(i) => &i.attrs,
        syn::Item::Struct(i) => &i.attrs,
        syn::Item::Trait(i) => &i.attrs,
        syn::Item::Type(i) => &i.attrs,
        syn::Item::Union(i) => &i.attrs,
        _ => return None,
    })
}

impl Graph {
    /// Reads the crate whose root file is `root` (`src/lib.rs`, `src/main.rs`).
    pub fn read(root: &Path) -> Result<Graph, String> {
        let mut g = Graph {
            files: Vec::new(),
            modules: Vec::new(),
        };
        g.read_file(root, None, None)?;
        Ok(g)
    }

    /// Reads `path` as the module `name` under `parent` (the root when `None`).
    fn read_file(&mut self, path: &Path, parent: Option<usize>, name: Option<String>) -> Result<(), String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let ast = syn::parse_file(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        self.files.push(path.to_owned());
        let file = self.files.len() - 1;
        // A root, `mod.rs` or `main.rs` holds its children beside it; `a.rs` in `a/`.
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let dir = if parent.is_none() || stem == "mod" {
            path.parent().unwrap().to_owned()
        } else {
            path.with_extension("")
        };
        self.read_items(&ast.items, file, &dir, parent, name)
    }

    /// Adds a module of `items` in `file` whose out-of-line children live in `dir`.
    fn read_items(
        &mut self,
        items: &[syn::Item],
        file: usize,
        dir: &Path,
        parent: Option<usize>,
        name: Option<String>,
    ) -> Result<(), String> {
        self.modules.push(Module {
            file,
            parent,
            ..Module::default()
        });
        let id = self.modules.len() - 1;
        if let (Some(p), Some(name)) = (parent, name) {
            self.modules[p].children.insert(name, id);
        }
        let mut module = std::mem::take(&mut self.modules[id]);
        for item in items {
            if item_attrs(item).is_some_and(is_test) {
                continue;
            }
            if let Some(n) = item_name(item) {
                module.defs.insert(n);
            }
        }
        let mut paths = Paths { module: &mut module };
        for item in items {
            paths.visit_item(item);
        }
        self.modules[id] = module;
        for item in items {
            let syn::Item::Mod(m) = item else { continue };
            if is_test(&m.attrs) {
                continue;
            }
            let child = m.ident.to_string();
            match &m.content {
                Some((_, inner)) => self.read_items(inner, file, &dir.join(&child), Some(id), Some(child))?,
                None => {
                    let flat = dir.join(format!("{child}.rs"));
                    let nested = dir.join(&child).join("mod.rs");
                    let path = if flat.exists() { flat } else { nested };
                    self.read_file(&path, Some(id), Some(child))?;
                }
            }
        }
        Ok(())
    }

    /// Where `path`, written in module `m`, leads.
    fn resolve(&self, m: usize, path: &[String], depth: u32) -> Option<Target> {
        if depth > 32 || path.is_empty() {
            return None;
        }
        let module = &self.modules[m];
        let (first, rest) = (path[0].as_str(), &path[1..]);
        match first {
            "crate" => self.walk(0, rest, depth),
            "self" => self.walk(m, rest, depth),
            "super" => self.walk(module.parent?, rest, depth),
            _ => self.walk(m, path, depth),
        }
    }

    /// Follows `path` from inside module `m`.
    fn walk(&self, m: usize, path: &[String], depth: u32) -> Option<Target> {
        let module = &self.modules[m];
        let Some(first) = path.first() else {
            return Some(Target::Module(m));
        };
        let rest = &path[1..];
        if first == "super" {
            return self.walk(module.parent?, rest, depth + 1);
        }
        if first == "self" {
            return self.walk(m, rest, depth + 1);
        }
        if let Some(&child) = module.children.get(first) {
            return self.walk(child, rest, depth + 1);
        }
        if module.defs.contains(first) {
            return Some(Target::Item(module.file));
        }
        if let Some((target, _)) = module.imports.get(first) {
            let mut full = target.clone();
            full.extend_from_slice(rest);
            return self.resolve(m, &full, depth + 1);
        }
        module.globs.iter().find_map(|g| match self.resolve(m, g, depth + 1) {
            Some(Target::Module(gm)) if gm != m => self.walk(gm, path, depth + 1),
            _ => None,
        })
    }

    /// Every use of a name across files.
    pub fn edges(&self) -> Vec<Edge> {
        let mut edges = BTreeSet::new();
        for (m, module) in self.modules.iter().enumerate() {
            let imported = module
                .imports
                .iter()
                .filter(|(_, (_, reexport))| !reexport)
                .map(|(_, (path, _))| path);
            let inline = module.uses.iter().filter(|p| {
                // A single name is a local, an import (counted above) or a glob's.
                p.len() >= 2
                    || (!module.defs.contains(&p[0]) && !module.imports.contains_key(&p[0]) && !module.globs.is_empty())
            });
            for path in imported.chain(inline) {
                if let Some(Target::Item(to)) = self.resolve(m, path, 0)
                    && to != module.file
                {
                    edges.insert(Edge {
                        from: self.files[module.file].clone(),
                        to: self.files[to].clone(),
                        name: path.join("::"),
                    });
                }
            }
        }
        edges.into_iter().collect()
    }

    /// The circles: every strongly connected set of two or more files, with the uses
    /// inside it.
    pub fn circles(&self) -> Vec<Vec<Edge>> {
        let edges = self.edges();
        let index: BTreeMap<&PathBuf, usize> = self.files.iter().enumerate().map(|(i, f)| (f, i)).collect();
        let mut next: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); self.files.len()];
        for e in &edges {
            next[index[&e.from]].insert(index[&e.to]);
        }
        let component = strongly_connected(&next);
        let mut sets: BTreeMap<usize, Vec<Edge>> = BTreeMap::new();
        for e in &edges {
            let (a, b) = (component[index[&e.from]], component[index[&e.to]]);
            if a == b {
                sets.entry(a).or_default().push(e.clone());
            }
        }
        sets.into_values().collect()
    }
}

/// The strongly connected component of each node, named by one of its nodes (Tarjan's
/// algorithm, with an explicit stack).
fn strongly_connected(next: &[BTreeSet<usize>]) -> Vec<usize> {
    /// Tarjan's bookkeeping.
    struct State {
        index: Vec<usize>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        component: Vec<usize>,
        counter: usize,
        stack: Vec<usize>,
        /// The nodes being visited and the successors each still has to visit.
        frames: Vec<(usize, Vec<usize>)>,
    }
    impl State {
        fn enter(&mut self, v: usize, next: &[BTreeSet<usize>]) {
            (self.index[v], self.low[v]) = (self.counter, self.counter);
            self.counter += 1;
            self.stack.push(v);
            self.on_stack[v] = true;
            self.frames.push((v, next[v].iter().rev().copied().collect()));
        }
    }
    let n = next.len();
    let mut s = State {
        index: vec![usize::MAX; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        component: vec![usize::MAX; n],
        counter: 0,
        stack: Vec::new(),
        frames: Vec::new(),
    };
    for start in 0..n {
        if s.index[start] != usize::MAX {
            continue;
        }
        s.enter(start, next);
        while let Some((v, todo)) = s.frames.last_mut() {
            let v = *v;
            if let Some(w) = todo.pop() {
                if s.index[w] == usize::MAX {
                    s.enter(w, next);
                } else if s.on_stack[w] {
                    s.low[v] = s.low[v].min(s.index[w]);
                }
                continue;
            }
            s.frames.pop();
            if let Some(&(parent, _)) = s.frames.last() {
                s.low[parent] = s.low[parent].min(s.low[v]);
            }
            if s.low[v] == s.index[v] {
                while let Some(w) = s.stack.pop() {
                    s.on_stack[w] = false;
                    s.component[w] = v;
                    if w == v {
                        break;
                    }
                }
            }
        }
    }
    s.component
}

#[cfg(test)]
mod tests {
    use super::strongly_connected;
    use std::collections::BTreeSet;

    #[test]
    fn tarjan_finds_the_circle_and_leaves_the_rest_alone() {
        // 0 → 1 → 2 → 0, 2 → 3, 3 → 4.
        let next: Vec<BTreeSet<usize>> = vec![[1].into(), [2].into(), [0, 3].into(), [4].into(), [].into()];
        let c = strongly_connected(&next);
        assert_eq!((c[0], c[1]), (c[2], c[2]));
        assert!(c[3] != c[0] && c[4] != c[3] && c[4] != c[0]);
    }
}
