//! `docs/tuning.md` lists every field of the core's tuning table (`evorec_core::tuning::FIELDS`)
//! with its default as `evorec config` prints it, and no field the table does not have.

use std::collections::BTreeMap;

use evorec_core::tuning::{FIELDS, Tuning};
use evorec_sim::sim::scenario::TrackerTable;

/// `name → default` of every row of a Markdown table whose first cell is a backticked name.
fn documented(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            (cells[1].trim_matches('`').to_owned(), cells.get(3).copied().unwrap_or_default().to_owned())
        })
        .collect()
}

/// `name → value` of `evorec config`'s output.
fn printed() -> BTreeMap<String, String> {
    TrackerTable(Tuning::DEFAULT)
        .to_toml()
        .lines()
        .filter_map(|l| l.split_once(" = "))
        .map(|(k, v)| (k.to_owned(), v.to_owned()))
        .collect()
}

#[test]
fn tuning_md_lists_every_field_with_its_default_and_nothing_else() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/tuning.md");
    let doc = documented(&std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}")));
    let printed = printed();
    assert_eq!(printed.len(), FIELDS.len());
    for f in &FIELDS {
        let default = doc.get(f.name).unwrap_or_else(|| panic!("docs/tuning.md does not list `{}`", f.name));
        assert_eq!(default, &printed[f.name], "docs/tuning.md's default of `{}`", f.name);
    }
    let stale: Vec<&String> = doc.keys().filter(|k| !printed.contains_key(*k)).collect();
    assert!(stale.is_empty(), "docs/tuning.md lists fields the table does not have: {stale:?}");
}
