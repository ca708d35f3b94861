//! `docs/registers.md` and `docs/interface.md` are committed: `cargo test --workspace`
//! (and so `make test`) fails here when they no longer match `hdl/registers.toml` and
//! `hdl/interface.toml`.

use finestep_regmap::{
    check_docs, default_root, DocsCheckError, DOCS_PATH, INTERFACE_DOCS_PATH, INTERFACE_PATH, MAP_PATH,
};
use std::path::{Path, PathBuf};

#[test]
fn committed_docs_match_the_map() {
    if let Err(error) = check_docs(&default_root()) {
        panic!("{error}");
    }
}

/// A scratch repository root holding the real map and the given docs text (none when
/// `docs` is `None`).
fn scratch_root(test: &str, docs: Option<&str>) -> PathBuf {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("regmap-docs-{test}"));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("hdl")).unwrap();
    std::fs::copy(default_root().join(MAP_PATH), root.join(MAP_PATH)).unwrap();
    std::fs::copy(default_root().join(INTERFACE_PATH), root.join(INTERFACE_PATH)).unwrap();
    if let Some(docs) = docs {
        std::fs::create_dir_all(root.join("docs")).unwrap();
        std::fs::write(root.join(DOCS_PATH), docs).unwrap();
        let (_, interface) = finestep_regmap::load_interface(&default_root()).unwrap();
        std::fs::write(root.join(INTERFACE_DOCS_PATH), finestep_regmap::interface_markdown::generate(&interface))
            .unwrap();
    }
    root
}

fn generated_docs() -> String {
    let map = finestep_regmap::load_map(&default_root()).unwrap();
    finestep_regmap::markdown::generate(&map)
}

#[test]
fn an_edited_line_is_reported_with_its_number_and_the_fix() {
    let edited = generated_docs().replacen("| 0 | RUN | rw | 0 |", "| 0 | RUN | rw | 1 |", 1);
    let line = edited.lines().position(|line| line.starts_with("| 0 | RUN | rw | 1 |")).unwrap() + 1;
    let root = scratch_root("edited", Some(&edited));
    match check_docs(&root) {
        Err(error @ DocsCheckError::Stale { .. }) => {
            let DocsCheckError::Stale { line: reported, .. } = &error else { unreachable!() };
            assert_eq!(*reported, line);
            let message = error.to_string();
            assert!(message.contains("docs/registers.md is stale"), "{message}");
            assert!(message.contains("make regmap"), "{message}");
        }
        other => panic!("expected Stale, got {other:?}"),
    }
}

#[test]
fn a_truncated_file_is_stale() {
    let generated = generated_docs();
    let root = scratch_root("truncated", Some(&generated[..generated.len() / 2]));
    assert!(matches!(check_docs(&root), Err(DocsCheckError::Stale { .. })));
}

#[test]
fn a_missing_file_is_reported() {
    let root = scratch_root("missing", None);
    let error = check_docs(&root).unwrap_err();
    assert!(matches!(error, DocsCheckError::Unreadable { .. }), "{error:?}");
    assert!(error.to_string().contains("generate it with"), "{error}");
}

#[test]
fn a_fresh_copy_passes() {
    let root = scratch_root("fresh", Some(&generated_docs()));
    check_docs(&root).unwrap();
}

#[test]
fn a_stale_interface_page_is_reported() {
    let root = scratch_root("interface", Some(&generated_docs()));
    std::fs::write(root.join(INTERFACE_DOCS_PATH), "# an old copy\n").unwrap();
    let message = check_docs(&root).unwrap_err().to_string();
    assert!(message.contains("docs/interface.md is stale: line 1"), "{message}");
}
