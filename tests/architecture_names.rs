//! ARCHITECTURE.md quotes the code's names between backticks: every quoted
//! file must exist, and every quoted Rust name must be defined (`A::b`:
//! `b` defined in module `A`'s files, or beside type `A`), so that the page
//! stays true to the code when names change.

use std::fs;
use std::path::{Path, PathBuf};

/// Every file under `dir` (recursively) whose name ends with `ext`.
fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if !name.starts_with('.') && name != "target" && name != "build" && name != "node_modules" {
                files(&path, ext, out);
            }
        } else if name.ends_with(ext) {
            out.push(path);
        }
    }
}

/// Whether `text` defines `name`: an item, a macro, or a field or enum
/// variant at the start of a line.
fn defines(text: &str, name: &str) -> bool {
    let word = |s: &str, at: usize| {
        let end = at + name.len();
        s[end..].chars().next().is_none_or(|c| !(c.is_alphanumeric() || c == '_'))
    };
    for key in ["fn ", "struct ", "enum ", "trait ", "const ", "static ", "type ", "mod ", "macro_rules! "] {
        let pattern = format!("{key}{name}");
        if text.match_indices(&pattern).any(|(at, _)| word(text, at + key.len())) {
            return true;
        }
    }
    text.lines().any(|line| {
        let line = line.trim_start();
        let line = line.strip_prefix("pub(crate) ").or_else(|| line.strip_prefix("pub(super) ")).unwrap_or(line);
        let line = line.strip_prefix("pub ").unwrap_or(line);
        line.starts_with(name) && line[name.len()..].trim_start().starts_with([':', ',', '(', '{'])
    })
}

#[test]
fn every_name_the_architecture_quotes_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let page = fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut rust = Vec::new();
    files(&root.join("src"), ".rs", &mut rust);
    let sources: Vec<(PathBuf, String)> =
        rust.into_iter().map(|p| (p.clone(), fs::read_to_string(p).unwrap())).collect();
    let mut all_files = Vec::new();
    files(root, "", &mut all_files);
    let texts: Vec<String> = all_files
        .iter()
        .filter(|p| {
            p.extension().is_some_and(|e| {
                ["rs", "py", "sh", "txt", "cmake", "cpp", "h", "js", "mjs"].contains(&e.to_str().unwrap_or(""))
            })
        })
        .filter_map(|p| fs::read_to_string(p).ok())
        .collect();
    let module_files = |module: &str| -> Vec<&(PathBuf, String)> {
        sources
            .iter()
            .filter(|(p, _)| {
                p.file_stem().is_some_and(|s| s == module) || p.components().any(|c| c.as_os_str() == module)
            })
            .collect()
    };
    let type_files = |ty: &str| -> Vec<&(PathBuf, String)> {
        let dirs: Vec<&Path> = sources
            .iter()
            .filter(|(_, t)| {
                ["struct ", "enum ", "trait "].iter().any(|k| defines(t, ty) && t.contains(&format!("{k}{ty}")))
            })
            .filter_map(|(p, _)| p.parent())
            .collect();
        sources.iter().filter(|(p, _)| dirs.iter().any(|d| p.starts_with(d))).collect()
    };
    let mut missing = Vec::new();
    for quoted in page.split('`').skip(1).step_by(2) {
        let q = quoted.trim_end_matches('!');
        let skip = q.is_empty()
            || q.contains(|c: char| " *(<#\"".contains(c))
            || q.starts_with("--")
            || q.starts_with("..")
            || q.contains('X')
            || q.ends_with("::");
        if skip {
            continue;
        }
        let is_path = q.contains('/')
            || [".rs", ".md", ".h", ".cpp", ".js", ".mjs", ".sh", ".vert"].iter().any(|e| q.ends_with(e));
        if is_path {
            let rel = q.trim_end_matches('/');
            let found = root.join(rel).exists()
                || root.join("src").join(rel).exists()
                || all_files.iter().any(|p| p.ends_with(rel) || p.parent().is_some_and(|d| d.ends_with(rel)));
            if !found {
                missing.push(q.to_string());
            }
            continue;
        }
        let segments: Vec<&str> = q.split("::").filter(|s| *s != "crate").collect();
        let name = *segments.last().unwrap();
        let found = match segments.len() {
            1 => {
                !module_files(name).is_empty()
                    || sources.iter().any(|(_, t)| defines(t, name) || t.contains(name))
                    || texts.iter().any(|t| t.contains(name))
            }
            _ => {
                let owner = segments[segments.len() - 2];
                let mut scope = module_files(owner);
                scope.extend(type_files(owner));
                scope.iter().any(|(_, t)| defines(t, name))
            }
        };
        if !found {
            missing.push(q.to_string());
        }
    }
    assert!(missing.is_empty(), "ARCHITECTURE.md quotes names the code does not have: {missing:?}");
}
