//! The house rules of `src/`, checked on every `cargo test` (ARCHITECTURE.md, "Layering").
//!
//! Every `use crate::…`, `super::…` and `crate::…` path in the library is resolved to
//! the file that defines what it names (following `use` and `pub use` re-exports), and
//!
//! * an import that crosses into a folder its folder may not depend on ([`RULES`]),
//! * a cycle of imports between files,
//! * a thread, channel, socket, device or clock in a module that must stay pure
//!   ([`PURE`]),
//! * a file in a folder no rule covers,
//!
//! fails the test, naming the file and line. The same idea as ArchUnit's layer rules or
//! a cargo-deny ban list, applied to our own modules.
//!
//! The binary (`src/main.rs`, `src/cli.rs`, `src/cli/`) sits above everything and
//! imports the library as `crowdtouch::…`; its own files are held to two rules
//! ([`check_binary`]): no cycle of imports between files, and each command family
//! (a folder `src/cli/<family>/` or file `src/cli/<family>.rs`) imports only its own
//! files and the shared `src/cli/common/`, never another family or the dispatch in
//! `src/cli.rs`; `common` imports no family.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;
use syn::spanned::Spanned;
use syn::visit::Visit;

/// One folder (or top-level file) of `src/` and what it may import besides its own
/// folder. The most specific rule applies: `crowd::mesh` is held to its own list, not
/// to `crowd`'s.
struct Rule {
    module: &'static str,
    may_use: &'static [&'static str],
}

/// Dependencies point one way: cli → pipeline → {engine, publish, input, config} →
/// {gesture, crowd} → {geom, vocab and the other bottom modules}.
#[rustfmt::skip]
const RULES: &[Rule] = &[
    // The bottom. geom, rng, sys and located import nothing from the crate; vocab
    // names geometry; rt (the clock and scheduling) speaks vocab's time.
    Rule { module: "geom", may_use: &[] },
    Rule { module: "rng", may_use: &[] },
    Rule { module: "sys", may_use: &[] },
    Rule { module: "located", may_use: &[] },
    // Pictures draw world geometry and nothing else.
    Rule { module: "picture", may_use: &["geom"] },
    Rule { module: "vocab", may_use: &["geom"] },
    Rule { module: "rt", may_use: &["vocab"] },
    // The pure cores: plain functions of their inputs and `now`.
    Rule { module: "gesture", may_use: &["vocab", "geom", "rng", "located"] },
    Rule { module: "crowd", may_use: &["gesture", "vocab", "geom", "rng", "located"] },
    Rule { module: "crowd::mesh", may_use: &["geom", "rng"] },
    Rule { module: "crowd::assign", may_use: &["geom", "rng"] },
    Rule { module: "crowd::environment", may_use: &["crowd::assign", "vocab", "geom", "rng", "located"] },
    Rule { module: "crowd::formation", may_use: &["crowd::mesh", "crowd::assign", "geom", "rng"] },
    Rule {
        module: "crowd::motion",
        may_use: &["crowd::mesh", "crowd::assign", "crowd::agents", "gesture", "vocab", "geom", "rng"],
    },
    Rule {
        module: "crowd::transform",
        may_use: &["crowd::mesh", "crowd::assign", "crowd::environment", "crowd::formation", "crowd::agents", "vocab", "geom", "rng"],
    },
    Rule {
        module: "crowd::edit",
        may_use: &["crowd::mesh", "crowd::environment", "located", "geom", "rng"],
    },
    Rule {
        module: "crowd::control",
        may_use: &["crowd::mesh", "crowd::assign", "crowd::environment", "crowd::formation", "crowd::transform", "gesture", "vocab", "geom", "rng"],
    },
    // The edges, and the core that drives the crowd.
    Rule { module: "input", may_use: &["vocab", "geom", "rng", "sys", "rt", "located"] },
    Rule { module: "config", may_use: &["crowd", "gesture", "vocab", "geom", "located"] },
    Rule { module: "engine", may_use: &["config", "crowd", "gesture", "vocab", "geom", "located"] },
    Rule { module: "publish", may_use: &["vocab", "geom", "rt", "located"] },
    // The wiring.
    Rule {
        module: "pipeline",
        may_use: &["engine", "publish", "input", "config", "crowd", "gesture", "vocab", "geom", "rng", "rt", "sys"],
    },
];

/// Modules that know nothing of threads, channels, sockets, devices or the clock:
/// they are given `now` and their inputs, so replays are deterministic and the cores
/// are tested as plain functions.
const PURE: &[&str] = &[
    "gesture", "crowd", "engine", "vocab", "geom", "located", "picture",
];

/// Paths a [`PURE`] module may not name (prefixes, on `::` boundaries).
const IMPURE_PATHS: &[&str] = &[
    "std::thread",
    "std::sync::mpsc",
    "std::sync::Mutex",
    "std::sync::RwLock",
    "std::sync::Condvar",
    "std::net",
    "std::os::unix::net",
    "std::time::Instant",
    "std::time::SystemTime",
    "crossbeam_channel",
    "hidapi",
    "evdev",
    "nix",
    "signal_hook",
    "crate::rt",
];

#[test]
fn src_follows_the_layering_rules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    read_tree(&src, &src, &mut files);
    assert!(files.len() > 20, "read {} files under src/", files.len());
    assert_no_problems(files, check, "layering problem(s) in src/");
}

/// Runs `check` on `files` and fails listing every problem it finds, `what` naming
/// them.
fn assert_no_problems(
    files: BTreeMap<String, String>,
    check: fn(&BTreeMap<String, String>) -> Vec<String>,
    what: &str,
) {
    // syn's parser and visitor recurse deeply on long expressions in debug builds.
    let problems = std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(move || check(&files))
        .expect("checker thread")
        .join()
        .expect("checker ran");
    assert!(
        problems.is_empty(),
        "{} {what} (rules: tests/architecture.rs, ARCHITECTURE.md):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn a_planted_forbidden_import_is_named_with_its_line() {
    let files = tree(&[
        ("lib.rs", "pub mod crowd;\npub mod input;\npub mod geom;\n"),
        ("geom.rs", "pub struct Vec2;\n"),
        ("input/mod.rs", "pub struct ContactId(pub u32);\n"),
        ("crowd/mod.rs", "pub mod direct;\n"),
        (
            "crowd/direct.rs",
            "use crate::geom::Vec2;\n\nuse crate::input::ContactId;\npub fn f(_: Vec2, _: ContactId) {}\n",
        ),
    ]);
    let problems = check(&files);
    assert_eq!(problems.len(), 1, "{problems:#?}");
    assert!(
        problems[0].starts_with("src/crowd/direct.rs:3: crowd may not depend on input"),
        "{}",
        problems[0]
    );
}

#[test]
fn a_cycle_through_a_re_export_is_found() {
    let files = tree(&[
        ("lib.rs", "pub mod publish;\n"),
        (
            "publish/mod.rs",
            "mod client;\nmod server;\npub use server::Stats;\npub struct Hello;\n",
        ),
        (
            "publish/server.rs",
            "use super::client::Client;\npub struct Stats(Client);\n",
        ),
        (
            "publish/client.rs",
            "use crate::publish::Stats;\npub struct Client(Box<Stats>);\n",
        ),
    ]);
    let problems = check(&files);
    assert_eq!(problems.len(), 1, "{problems:#?}");
    let p = &problems[0];
    assert!(p.starts_with("import cycle:"), "{p}");
    assert!(
        p.contains("src/publish/client.rs:1 → src/publish/server.rs"),
        "{p}"
    );
    assert!(
        p.contains("src/publish/server.rs:1 → src/publish/client.rs"),
        "{p}"
    );
    // The facade's own re-export is not part of the cycle: `Stats` is defined in server.rs.
    assert!(!p.contains("mod.rs"), "{p}");
}

#[test]
fn threads_and_clocks_in_a_pure_module_are_named() {
    let files = tree(&[
        ("lib.rs", "pub mod gesture;\npub mod rt;\n"),
        ("rt.rs", "pub fn monotonic_now() -> u64 { 0 }\n"),
        (
            "gesture/mod.rs",
            "use std::thread;\nfn f() -> u64 { crate::rt::monotonic_now() }\n",
        ),
    ]);
    let problems = check(&files);
    assert_eq!(problems.len(), 3, "{problems:#?}");
    let starts = [
        "src/gesture/mod.rs:1: gesture is pure",
        "src/gesture/mod.rs:2: gesture is pure",
        "src/gesture/mod.rs:2: gesture may not depend on rt",
    ];
    for s in starts {
        assert!(
            problems.iter().any(|p| p.starts_with(s)),
            "{s}: {problems:#?}"
        );
    }
}

#[test]
fn the_binary_keeps_its_families_apart_and_has_no_cycles() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    for f in ["main.rs", "cli.rs"] {
        let text = std::fs::read_to_string(src.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        files.insert(f.to_string(), text);
    }
    read_rs_files(&src, &src.join("cli"), &|_| true, &mut files);
    assert!(files.len() > 40, "read {} files of the binary", files.len());
    assert_no_problems(files, check_binary, "problem(s) in the binary");
}

/// A small binary: the dispatch, two families and `common`.
fn binary(extra: &[(&str, &str)]) -> BTreeMap<String, String> {
    let mut files = tree(&[
        ("main.rs", "mod cli;\nfn main() { cli::main(); }\n"),
        (
            "cli.rs",
            "mod common;\nmod daemon;\nmod scenes;\npub fn main() { daemon::run::run(); scenes::render::render(); }\n",
        ),
        ("cli/common/mod.rs", "pub mod output;\n"),
        ("cli/common/output.rs", "pub fn outln() {}\n"),
        ("cli/daemon/mod.rs", "pub mod run;\npub mod check;\n"),
        (
            "cli/daemon/run.rs",
            "use crate::cli::common::output::outln;\nuse super::check::check;\npub fn run() { outln(); check(); }\n",
        ),
        ("cli/daemon/check.rs", "pub fn check() {}\n"),
        ("cli/scenes/mod.rs", "pub mod render;\n"),
        ("cli/scenes/render.rs", "pub fn render() {}\n"),
    ]);
    for (p, s) in extra {
        files.insert(p.to_string(), s.to_string());
    }
    files
}

#[test]
fn a_planted_import_between_two_families_is_named_with_its_line() {
    assert_eq!(check_binary(&binary(&[])), Vec::<String>::new());
    let p = check_binary(&binary(&[(
        "cli/scenes/render.rs",
        "\nuse crate::cli::daemon::check::check;\npub fn render() { check(); }\n",
    )]));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(
        p[0].starts_with(
            "src/cli/scenes/render.rs:2: command family `scenes` may not import family `daemon`"
        ),
        "{}",
        p[0]
    );
    let p = check_binary(&binary(&[(
        "cli/common/output.rs",
        "use crate::cli::scenes::render::render;\npub fn outln() { render(); }\n",
    )]));
    assert!(
        p.iter()
            .any(|l| l.contains("cli/common is shared by every family")),
        "{p:?}"
    );
}

#[test]
fn a_planted_cycle_in_cli_is_found() {
    let p = check_binary(&binary(&[(
        "cli/daemon/check.rs",
        "use super::run::run;\npub fn check() { run(); }\n",
    )]));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("import cycle:"), "{}", p[0]);
    assert!(
        p[0].contains("src/cli/daemon/check.rs:1 → src/cli/daemon/run.rs"),
        "{}",
        p[0]
    );
    assert!(
        p[0].contains("src/cli/daemon/run.rs:2 → src/cli/daemon/check.rs"),
        "{}",
        p[0]
    );
}

fn tree(files: &[(&str, &str)]) -> BTreeMap<String, String> {
    files
        .iter()
        .map(|(p, s)| (p.to_string(), s.to_string()))
        .collect()
}

/// Every `.rs` file of the library under `dir`, by path relative to `src/`; the
/// binary (`main.rs`, `cli/`) is left out.
fn read_tree(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
    let library = |rel: &str| !matches!(rel, "main.rs" | "cli" | "cli.rs");
    read_rs_files(root, dir, &library, out);
}

/// Every `.rs` file under `dir` whose path relative to `root` (and every folder on
/// the way) `keep` accepts, by that path.
fn read_rs_files(
    root: &Path,
    dir: &Path,
    keep: &dyn Fn(&str) -> bool,
    out: &mut BTreeMap<String, String>,
) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        let rel = p
            .strip_prefix(root)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        if !keep(&rel) {
            continue;
        }
        if p.is_dir() {
            read_rs_files(root, &p, keep, out);
        } else if rel.ends_with(".rs") {
            let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{rel}: {e}"));
            out.insert(rel, text);
        }
    }
}

/// The module path of a file: `crowd/assign/mod.rs` → `crowd::assign`.
fn module_of(rel: &str) -> Vec<String> {
    let mut segs: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(str::to_string)
        .collect();
    if matches!(
        segs.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        segs.pop();
    }
    segs
}

/// A path as written, where it was written, and whether it is a `use`.
struct Mention {
    segs: Vec<String>,
    line: usize,
    /// The module (file module plus inline modules) it was written in.
    module: Vec<String>,
    /// A glob import (`use x::*`): depends on the whole module.
    glob: bool,
}

/// What one module (a file, or an inline `mod x { … }`) defines and imports.
#[derive(Default)]
struct ModuleInfo {
    file: String,
    /// Items defined here (structs, fns, consts, inline modules, …).
    items: BTreeSet<String>,
    /// Names bound by `use` (name → path as written, relative to this module).
    bindings: HashMap<String, Vec<String>>,
    /// `use x::*` targets, as written.
    globs: Vec<Vec<String>>,
}

struct Collector<'a> {
    file: &'a str,
    stack: Vec<String>,
    modules: &'a mut BTreeMap<Vec<String>, ModuleInfo>,
    mentions: Vec<Mention>,
}

impl Collector<'_> {
    fn module(&mut self) -> &mut ModuleInfo {
        let key = self.stack.clone();
        let file = self.file.to_string();
        self.modules.entry(key).or_insert_with(|| ModuleInfo {
            file,
            ..ModuleInfo::default()
        })
    }

    fn define(&mut self, name: String) {
        self.module().items.insert(name);
    }

    fn use_tree(&mut self, prefix: &mut Vec<String>, tree: &syn::UseTree, line: usize) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                self.use_tree(prefix, &p.tree, line);
                prefix.pop();
            }
            syn::UseTree::Name(n) => {
                let name = n.ident.to_string();
                let mut path = prefix.clone();
                let bound = if name == "self" {
                    prefix.last().cloned().unwrap_or_default()
                } else {
                    path.push(name.clone());
                    name
                };
                self.record_use(path, bound, line);
            }
            syn::UseTree::Rename(r) => {
                let mut path = prefix.clone();
                if r.ident != "self" {
                    path.push(r.ident.to_string());
                }
                self.record_use(path, r.rename.to_string(), line);
            }
            syn::UseTree::Glob(_) => {
                let path = prefix.clone();
                self.module().globs.push(path.clone());
                self.mentions.push(Mention {
                    segs: path,
                    line,
                    module: self.stack.clone(),
                    glob: true,
                });
            }
            syn::UseTree::Group(g) => {
                for t in &g.items {
                    self.use_tree(prefix, t, line);
                }
            }
        }
    }

    fn record_use(&mut self, path: Vec<String>, bound: String, line: usize) {
        if bound != "_" {
            self.module().bindings.insert(bound, path.clone());
        }
        self.mentions.push(Mention {
            segs: path,
            line,
            module: self.stack.clone(),
            glob: false,
        });
    }
}

impl<'ast> Visit<'ast> for Collector<'_> {
    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        let line = u.span().start().line;
        let mut prefix = Vec::new();
        if u.leading_colon.is_some() {
            prefix.push(String::new());
        }
        self.use_tree(&mut prefix, &u.tree, line);
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        let name = m.ident.to_string();
        self.define(name.clone());
        if let Some((_, items)) = &m.content {
            self.stack.push(name);
            self.module();
            for i in items {
                self.visit_item(i);
            }
            self.stack.pop();
        }
    }

    fn visit_item(&mut self, i: &'ast syn::Item) {
        let name = match i {
            syn::Item::Const(x) => Some(x.ident.to_string()),
            syn::Item::Enum(x) => Some(x.ident.to_string()),
            syn::Item::Fn(x) => Some(x.sig.ident.to_string()),
            syn::Item::Macro(x) => x.ident.as_ref().map(ToString::to_string),
            syn::Item::Static(x) => Some(x.ident.to_string()),
            syn::Item::Struct(x) => Some(x.ident.to_string()),
            syn::Item::Trait(x) => Some(x.ident.to_string()),
            syn::Item::Type(x) => Some(x.ident.to_string()),
            syn::Item::Union(x) => Some(x.ident.to_string()),
            _ => None,
        };
        if let Some(n) = name {
            self.define(n);
        }
        syn::visit::visit_item(self, i);
    }

    fn visit_path(&mut self, p: &'ast syn::Path) {
        if p.segments.len() > 1 || p.leading_colon.is_some() {
            let mut segs: Vec<String> = Vec::new();
            if p.leading_colon.is_some() {
                segs.push(String::new());
            }
            segs.extend(p.segments.iter().map(|s| s.ident.to_string()));
            self.mentions.push(Mention {
                segs,
                line: p.span().start().line,
                module: self.stack.clone(),
                glob: false,
            });
        }
        syn::visit::visit_path(self, p);
    }
}

/// The crate's modules, and resolution of paths to the files that define them.
struct Crate {
    modules: BTreeMap<Vec<String>, ModuleInfo>,
}

impl Crate {
    /// `segs` as written in `module`, made absolute (`None`: another crate).
    fn absolute(&self, module: &[String], segs: &[String]) -> Option<Vec<String>> {
        self.absolute_at(module, segs, 0)
    }

    fn absolute_at(&self, module: &[String], segs: &[String], depth: usize) -> Option<Vec<String>> {
        let first = segs.first()?;
        if depth > 16 {
            return None;
        }
        match first.as_str() {
            "" => None,
            "crate" => Some(segs[1..].to_vec()),
            "self" => Some([module, &segs[1..]].concat()),
            "super" => {
                let mut m = module.to_vec();
                let mut rest = segs;
                while rest.first().map(String::as_str) == Some("super") {
                    m.pop();
                    rest = &rest[1..];
                }
                Some([m.as_slice(), rest].concat())
            }
            _ => {
                let info = self.modules.get(module)?;
                let mut child = module.to_vec();
                child.push(first.clone());
                if self.modules.contains_key(&child) {
                    return Some([child.as_slice(), &segs[1..]].concat());
                }
                let bound = info.bindings.get(first)?;
                // A binding to itself (`use serde;`) names another crate.
                if bound.len() == 1 && bound[0] == *first {
                    return None;
                }
                let target = self.absolute_at(module, bound, depth + 1)?;
                Some([target.as_slice(), &segs[1..]].concat())
            }
        }
    }

    /// The file defining the absolute path `abs`, following re-exports.
    fn resolve(&self, abs: &[String], depth: usize) -> Option<&str> {
        if depth > 16 {
            return None;
        }
        let k = (0..=abs.len())
            .rev()
            .find(|&k| self.modules.contains_key(&abs[..k]))?;
        let module = &abs[..k];
        let info = &self.modules[module];
        let Some(name) = abs.get(k) else {
            return Some(&info.file);
        };
        if info.items.contains(name) {
            return Some(&info.file);
        }
        if let Some(bound) = info.bindings.get(name) {
            let target = self.absolute(module, bound)?;
            let rest = &abs[k + 1..];
            return self.resolve(&[target.as_slice(), rest].concat(), depth + 1);
        }
        for g in &info.globs {
            let Some(target) = self.absolute(module, g) else {
                continue;
            };
            if let Some(t) = self.modules.get(&target) {
                if t.items.contains(name) || t.bindings.contains_key(name) {
                    return self.resolve(&[target.as_slice(), &abs[k..]].concat(), depth + 1);
                }
            }
        }
        Some(&info.file)
    }
}

fn rule_for(module: &[String]) -> Option<&'static Rule> {
    RULES
        .iter()
        .filter(|r| under(module, r.module))
        .max_by_key(|r| r.module.len())
}

/// Whether `module` is `key` or inside it.
fn under(module: &[String], key: &str) -> bool {
    let k: Vec<&str> = key.split("::").collect();
    module.len() >= k.len() && module.iter().zip(&k).all(|(a, b)| a == b)
}

fn allowed(from: &Rule, to: &[String]) -> bool {
    under(to, from.module) || from.may_use.iter().any(|m| under(to, m))
}

fn starts_with(path: &[String], prefix: &str) -> bool {
    under(path, prefix)
}

/// Parses the files (paths relative to `src/`) of one crate: its modules, the
/// paths each file mentions, and one problem per file that does not parse.
fn parse(files: &BTreeMap<String, String>) -> (Crate, Vec<(String, Mention)>, Vec<String>) {
    let mut modules = BTreeMap::new();
    let mut mentions: Vec<(String, Mention)> = Vec::new();
    let mut problems = Vec::new();
    for (rel, text) in files {
        let ast = match syn::parse_file(text) {
            Ok(f) => f,
            Err(e) => {
                problems.push(format!(
                    "src/{rel}:{}: does not parse: {e}",
                    e.span().start().line
                ));
                continue;
            }
        };
        let mut c = Collector {
            file: rel,
            stack: module_of(rel),
            modules: &mut modules,
            mentions: Vec::new(),
        };
        c.module();
        c.visit_file(&ast);
        mentions.extend(c.mentions.into_iter().map(|m| (rel.clone(), m)));
    }
    (Crate { modules }, mentions, problems)
}

/// Checks the files (paths relative to `src/`); returns one line per problem.
fn check(files: &BTreeMap<String, String>) -> Vec<String> {
    let (krate, mentions, mut problems) = parse(files);
    let module_of_file: HashMap<&str, Vec<String>> = files
        .keys()
        .map(|rel| (rel.as_str(), module_of(rel)))
        .collect();

    for rel in files.keys() {
        let m = &module_of_file[rel.as_str()];
        if !m.is_empty() && rule_for(m).is_none() {
            problems.push(format!(
                "src/{rel}: no layering rule covers `{}`: add it to RULES in tests/architecture.rs and to ARCHITECTURE.md",
                m.join("::")
            ));
        }
    }

    // file → file → first line
    let mut edges: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    let mut seen = BTreeSet::new();
    for (rel, m) in &mentions {
        let from_module = &module_of_file[rel.as_str()];
        let rule = rule_for(from_module);
        let abs = krate.absolute(&m.module, &m.segs);
        // Purity: named paths, whether from this crate or another.
        if PURE.iter().any(|p| under(from_module, p)) {
            let named = match &abs {
                Some(a) => [vec!["crate".to_string()], a.clone()].concat(),
                None => m.segs.iter().filter(|s| !s.is_empty()).cloned().collect(),
            };
            if let Some(bad) = IMPURE_PATHS.iter().find(|p| starts_with(&named, p)) {
                let key = (rel.clone(), m.line, bad.to_string());
                if seen.insert(key) {
                    problems.push(format!(
                        "src/{rel}:{}: {} is pure (no threads, channels, sockets, devices or clock reads) but names `{}`",
                        m.line,
                        from_module.first().map_or("", String::as_str),
                        named.join("::")
                    ));
                }
            }
        }
        let Some(abs) = abs else { continue };
        // Naming a module (`use crate::input::evdev::{self as mt}`) depends on
        // nothing by itself: the items named through it are resolved on their own.
        if !m.glob && krate.modules.contains_key(&abs) {
            continue;
        }
        let Some(target) = krate.resolve(&abs, 0) else {
            continue;
        };
        if target == rel {
            continue;
        }
        let to_module = &module_of_file[target];
        if let Some(rule) = rule {
            if !allowed(rule, to_module) {
                let key = (rel.clone(), m.line, target.to_string());
                if seen.insert(key) {
                    let to_rule = rule_for(to_module).map_or("the crate root", |r| r.module);
                    problems.push(format!(
                        "src/{rel}:{}: {} may not depend on {} (`crate::{}` is in src/{target}); {} may use: {}",
                        m.line,
                        rule.module,
                        to_rule,
                        abs.join("::"),
                        rule.module,
                        if rule.may_use.is_empty() {
                            "nothing in the crate".to_string()
                        } else {
                            rule.may_use.join(", ")
                        }
                    ));
                }
            }
        }
        let e = edges.entry(rel.clone()).or_default();
        let line = e.entry(target.to_string()).or_insert(m.line);
        *line = (*line).min(m.line);
    }
    problems.sort_by_key(|p| natural_key(p));
    problems.extend(cycle_problems(&edges));
    problems
}

/// One problem per import cycle, each step with its file and line.
fn cycle_problems(edges: &BTreeMap<String, BTreeMap<String, usize>>) -> Vec<String> {
    let mut problems = Vec::new();
    for cycle in cycles(edges) {
        let mut s = String::from("import cycle:");
        for (i, f) in cycle.iter().enumerate() {
            let next = &cycle[(i + 1) % cycle.len()];
            let line = edges[f][next];
            s.push_str(&format!("\n  src/{f}:{line} → src/{next}"));
        }
        problems.push(s);
    }
    problems
}

/// The command family of a binary module: `cli::<family>::…` → `Some(family)`;
/// `None` for the dispatch (`cli`) and the root (`main`).
fn family(module: &[String]) -> Option<&str> {
    match module {
        [cli, fam, ..] if cli == "cli" => Some(fam.as_str()),
        _ => None,
    }
}

/// The family every other family may import.
const SHARED_FAMILY: &str = "common";

/// Checks the binary's files (paths relative to `src/`: `main.rs`, `cli.rs`,
/// `cli/…`): no import cycle between files, and a family imports only itself and
/// [`SHARED_FAMILY`] (which imports no family); no family imports the dispatch.
fn check_binary(files: &BTreeMap<String, String>) -> Vec<String> {
    let (krate, mentions, mut problems) = parse(files);
    let mut edges: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    let mut seen = BTreeSet::new();
    for (rel, m) in &mentions {
        // `crowdtouch::…` (the library) and other crates resolve to nothing here.
        let Some(abs) = krate.absolute(&m.module, &m.segs) else {
            continue;
        };
        if !m.glob && krate.modules.contains_key(&abs) {
            continue;
        }
        let Some(target) = krate.resolve(&abs, 0) else {
            continue;
        };
        if target == rel {
            continue;
        }
        let (from, to) = (module_of(rel), module_of(target));
        let why = match (family(&from), family(&to)) {
            (Some(f), Some(t)) if f == t => None,
            (Some(f), Some(t)) if f == SHARED_FAMILY => Some(format!(
                "cli/{f} is shared by every family and may not import family `{t}`"
            )),
            (Some(f), Some(t)) if t != SHARED_FAMILY => Some(format!(
                "command family `{f}` may not import family `{t}`: share it through cli/{SHARED_FAMILY}/"
            )),
            (Some(f), None) => Some(format!(
                "command family `{f}` may not import the dispatch or the root: move what it needs into cli/{SHARED_FAMILY}/"
            )),
            _ => None,
        };
        if let Some(why) = why {
            if seen.insert((rel.clone(), m.line, target.to_string())) {
                problems.push(format!(
                    "src/{rel}:{}: {why} (`crate::{}` is in src/{target})",
                    m.line,
                    abs.join("::")
                ));
            }
        }
        let e = edges.entry(rel.clone()).or_default();
        let line = e.entry(target.to_string()).or_insert(m.line);
        *line = (*line).min(m.line);
    }
    problems.sort_by_key(|p| natural_key(p));
    problems.extend(cycle_problems(&edges));
    problems
}

/// Sort key that puts `file:9` before `file:10`.
fn natural_key(s: &str) -> (String, usize) {
    let (file, rest) = s.split_once(':').unwrap_or((s, ""));
    let line = rest
        .split(':')
        .next()
        .and_then(|l| l.parse().ok())
        .unwrap_or(0);
    (file.to_string(), line)
}

/// One shortest cycle through each strongly connected component of more than one
/// file (Tarjan's algorithm, then a breadth-first search inside the component).
fn cycles(edges: &BTreeMap<String, BTreeMap<String, usize>>) -> Vec<Vec<String>> {
    let nodes: BTreeSet<&String> = edges
        .keys()
        .chain(edges.values().flat_map(|m| m.keys()))
        .collect();
    let nodes: Vec<&String> = nodes.into_iter().collect();
    let index: HashMap<&String, usize> = nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let succ: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| {
            edges
                .get(*n)
                .map(|m| m.keys().map(|t| index[t]).collect())
                .unwrap_or_default()
        })
        .collect();

    struct Tarjan<'a> {
        succ: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        sccs: Vec<Vec<usize>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: usize) {
            self.index[v] = Some(self.next);
            self.low[v] = self.next;
            self.next += 1;
            self.stack.push(v);
            self.on_stack[v] = true;
            for &w in &self.succ[v] {
                match self.index[w] {
                    None => {
                        self.visit(w);
                        self.low[v] = self.low[v].min(self.low[w]);
                    }
                    Some(iw) if self.on_stack[w] => self.low[v] = self.low[v].min(iw),
                    Some(_) => {}
                }
            }
            if Some(self.low[v]) == self.index[v] {
                let mut scc = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack[w] = false;
                    scc.push(w);
                    if w == v {
                        break;
                    }
                }
                if scc.len() > 1 {
                    self.sccs.push(scc);
                }
            }
        }
    }
    let n = nodes.len();
    let mut t = Tarjan {
        succ: &succ,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        sccs: Vec::new(),
    };
    for v in 0..n {
        if t.index[v].is_none() {
            t.visit(v);
        }
    }
    let mut out = Vec::new();
    for scc in &t.sccs {
        let members: BTreeSet<usize> = scc.iter().copied().collect();
        let start = *members.iter().next().expect("non-empty component");
        // Breadth-first from `start` back to `start` inside the component.
        let mut prev = vec![usize::MAX; n];
        let mut queue = std::collections::VecDeque::from([start]);
        let mut end = None;
        'bfs: while let Some(v) = queue.pop_front() {
            for &w in &succ[v] {
                if !members.contains(&w) {
                    continue;
                }
                if w == start {
                    end = Some(v);
                    break 'bfs;
                }
                if prev[w] == usize::MAX {
                    prev[w] = v;
                    queue.push_back(w);
                }
            }
        }
        let mut path = Vec::new();
        let mut v = end.expect("a component of more than one file has a cycle");
        while v != start {
            path.push(v);
            v = prev[v];
        }
        path.push(start);
        path.reverse();
        out.push(path.into_iter().map(|i| nodes[i].clone()).collect());
    }
    out
}
