//! The documents' numbers come from one source, so none can go stale unnoticed:
//!
//! - board timing, flash, static RAM and stack are stated only in `docs/results.md` and in the
//!   blocks `scripts/results.py` fills from the same runs (`<!-- generated:NAME -->` …
//!   `<!-- /generated -->`); every row of such a block in the README or `docs/` states what
//!   `docs/results.md` states, with the same commit stamp, and outside the blocks no document
//!   restates one of those numbers, an instruction count or byte size of six digits written
//!   with thousands separators, or milliseconds with decimals by hand;
//! - the seed sweeps' and the servo grid's figures (the belts, the `pr-iiwa-sway` bag over GA seeds,
//!   the converged servo cells) are stated in sentence blocks `scripts/results.py` writes into
//!   `docs/results.md` and copies into the documents: every block of a document that
//!   `docs/results.md` also holds is the same text, stamp and numbers alike, and the README holds
//!   the blocks `README_SENTENCE_BLOCKS` names;
//! - `docs/firmware.md` states the code's link protocol version
//!   (`evorec_firmware::protocol::VERSION`) and `CONFIG` payload size
//!   (`evorec_firmware::protocol::CONFIG_LEN`);
//! - the walked sample points per camera (`SurfaceStrips::WALKED_PER_CAMERA`) and the default
//!   `generations_per_frame` are the code's wherever a document states them.
//!
//! Reads only the repository (no network, no `../shared`). Every failure names the file, the line
//! and the number.

use std::path::{Path, PathBuf};

use evorec_core::limits::DEFAULT_GRID;
use evorec_core::model::SurfaceStrips;
use evorec_core::tuning::Tuning;
use evorec_firmware::protocol::{CONFIG_LEN, VERSION};

const RESULTS: &str = "docs/results.md";
const FIRMWARE: &str = "docs/firmware.md";
const TIMING: &str = "docs/timing.md";
const BLOCK_OPEN: &str = "<!-- generated:";
const BLOCK_CLOSE: &str = "<!-- /generated -->";

/// The sentence blocks the README states (each also in `docs/results.md`).
const README_SENTENCE_BLOCKS: [&str; 4] = ["belts-axial", "belt-reversing", "pr-seeds", "servo-reversing"];

/// Numbers of six or more digits (with thousands separators) that may stand outside the
/// generated blocks: sizes that follow from the code's constants, not from a run.
const ALLOWED_LARGE: [(&str, &str); 1] =
    [("153,600", "two 160×120 RGB565 pairs, and one 320×240 RGB565 image (2 B a pixel)")];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read(rel: &str) -> String {
    let path = root().join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The documents that may hold generated blocks or restate numbers: the README and every
/// Markdown file directly in `docs/` but `docs/results.md` (the source) and
/// `docs/lab-notes.md` (dated records, each of its own tree).
fn documents() -> Vec<String> {
    let mut md: Vec<String> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|name| name.ends_with(".md") && name != "results.md" && name != "lab-notes.md")
        .map(|name| format!("docs/{name}"))
        .collect();
    md.sort();
    md.insert(0, "README.md".to_string());
    md
}

/// `n` as the message states it: the number, or "no number".
fn shown<T: std::fmt::Display>(n: Option<T>) -> String {
    n.map_or_else(|| "no number".to_string(), |n| n.to_string())
}

/// 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text.get(..at).map_or(0, |s| s.matches('\n').count()) + 1
}

/// A `<!-- generated:NAME -->` … `<!-- /generated -->` block.
struct Block {
    name: String,
    line: usize,
    /// Byte range of the whole block, markers included.
    span: std::ops::Range<usize>,
    stamp: Option<String>,
    rows: Vec<(String, String)>,
}

/// Every generated block of `text` (the document `file`); an unclosed block fails.
fn blocks(file: &str, text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(start) = text.get(from..).and_then(|s| s.find(BLOCK_OPEN)).map(|i| i + from) {
        let line = line_of(text, start);
        let after = start + BLOCK_OPEN.len();
        let name_end = text[after..].find(" -->").map(|i| i + after);
        let close = text[after..].find(BLOCK_CLOSE).map(|i| i + after);
        let (Some(name_end), Some(close)) = (name_end, close) else {
            panic!("{file}:{line}: generated block not closed by `{BLOCK_CLOSE}`")
        };
        let body = &text[name_end..close];
        out.push(Block {
            name: text[after..name_end].to_string(),
            line,
            span: start..close + BLOCK_CLOSE.len(),
            stamp: stamp(body),
            rows: table_rows(body),
        });
        from = close + BLOCK_CLOSE.len();
    }
    out
}

/// The commit of a `… from the runs of commit STAMP; …` line.
fn stamp(text: &str) -> Option<String> {
    let (_, rest) = text.split_once("from the runs of commit ")?;
    Some(rest[..rest.find([';', '\n'])?].trim().to_string())
}

/// The (quantity, value) rows of the two-column tables in `text`, header and rule left out.
fn table_rows(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter(|l| l.starts_with("| "))
        .filter_map(|l| {
            let cells: Vec<&str> = l.trim().trim_matches('|').split('|').map(str::trim).collect();
            match cells[..] {
                [q, v] if q != "quantity" && !q.starts_with("---") => Some((q.to_string(), v.to_string())),
                _ => None,
            }
        })
        .collect()
}

/// `docs/results.md`'s board timing table and the commit stamp of its runs.
fn results_board() -> (Vec<(String, String)>, String) {
    let results = read(RESULTS);
    let stamp = stamp(&results).unwrap_or_else(|| panic!("{RESULTS} names the commit of its runs"));
    let (_, section) =
        results.split_once("## Board timing").unwrap_or_else(|| panic!("{RESULTS} has a board timing section"));
    let section = section.split("\n## ").next().unwrap_or_default();
    let rows = table_rows(section);
    assert!(rows.len() >= 6, "{RESULTS}: the board timing table has {} rows, at least 6", rows.len());
    (rows, stamp)
}

/// Every digit run of `text` with its byte offset, thousands separators (`,`) kept and a
/// decimal part (`.` and digits) included: `("965,623", at)`, `("12.81", at)`.
fn numbers(text: &str) -> Vec<(String, usize)> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let word_before = i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        if !bytes[i].is_ascii_digit() || word_before {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() {
            let joined = matches!(bytes[i], b',' | b'.') && bytes.get(i + 1).is_some_and(u8::is_ascii_digit);
            if bytes[i].is_ascii_digit() || joined {
                i += 1;
            } else {
                break;
            }
        }
        out.push((text[start..i].to_string(), start));
    }
    out
}

/// The unsigned integer that starts `text` after any `(` and spaces, if any.
fn leading_number(text: &str) -> Option<u64> {
    let digits: String = text.trim_start_matches(['(', ' ']).chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

#[test]
fn firmware_md_states_the_codes_protocol_version() {
    let text = read(FIRMWARE);
    let heading = "## Link protocol (version ";
    let at = text.find(heading).unwrap_or_else(|| panic!("{FIRMWARE} has a `{heading}N)` heading"));
    let stated = leading_number(&text[at + heading.len()..]);
    assert_eq!(
        stated,
        Some(u64::from(VERSION)),
        "{FIRMWARE}:{}: states link protocol version {}; the code's \
         evorec_firmware::protocol::VERSION (hil-stubs/src/protocol/mod.rs) is {VERSION}",
        line_of(&text, at),
        shown(stated)
    );
    // Any other mention of a version number in firmware.md, and of a protocol version in the
    // README, is the code's too.
    let readme = read("README.md");
    for (file, text, only_protocol_lines) in [(FIRMWARE, &text, false), ("README.md", &readme, true)] {
        let lower = text.to_lowercase();
        for (at, _) in lower.match_indices("version") {
            let line = line_of(text, at);
            let line_text = lower.lines().nth(line - 1).unwrap_or_default();
            if only_protocol_lines && !line_text.contains("protocol") {
                continue;
            }
            if let Some(n) = leading_number(&text[at + "version".len()..]) {
                assert_eq!(
                    n,
                    u64::from(VERSION),
                    "{file}:{line}: states link protocol version {n}; the code's \
                     evorec_firmware::protocol::VERSION is {VERSION}"
                );
            }
        }
    }
}

#[test]
fn firmware_md_states_the_codes_config_size() {
    let text = read(FIRMWARE);
    let marker = " B (`CONFIG_LEN`)";
    let at = text.find(marker).unwrap_or_else(|| panic!("{FIRMWARE} states `CONFIG`'s size as \"N{marker}\""));
    let digits: String = text[..at].chars().rev().take_while(char::is_ascii_digit).collect();
    let stated: Option<usize> = digits.chars().rev().collect::<String>().parse().ok();
    assert_eq!(
        stated,
        Some(CONFIG_LEN),
        "{FIRMWARE}:{}: states a `CONFIG` payload of {} B; the code's \
         evorec_firmware::protocol::CONFIG_LEN is {CONFIG_LEN} B",
        line_of(&text, at),
        shown(stated)
    );
}

#[test]
fn generated_blocks_state_what_docs_results_states() {
    let (board, results_stamp) = results_board();
    let results = read(RESULTS);
    let sources = blocks(RESULTS, &results);
    let mut seen = Vec::new();
    for file in documents() {
        let text = read(&file);
        for block in blocks(&file, &text) {
            let at = format!("{file}:{} (generated block `{}`)", block.line, block.name);
            assert_eq!(
                block.stamp.as_deref(),
                Some(results_stamp.as_str()),
                "{at}: stamped with the runs of commit {}, {RESULTS} with {results_stamp}: rerun \
                 `scripts/results.py --blocks-only`",
                shown(block.stamp.as_deref())
            );
            seen.push((file.clone(), block.name.clone()));
            if let Some(source) = sources.iter().find(|b| b.name == block.name) {
                same_sentences(&at, &text[block.span.clone()], &results[source.span.clone()], source.line);
                continue;
            }
            assert!(!block.rows.is_empty(), "{at}: holds no rows: rerun `scripts/results.py --blocks-only`");
            for (quantity, value) in &block.rows {
                let source = board.iter().find(|(q, _)| q == quantity).map(|(_, v)| v);
                assert_eq!(
                    Some(value),
                    source,
                    "{at}: states {quantity} = {value}; {RESULTS} states {} \
                     (rerun `scripts/results.py --blocks-only`, do not edit the block)",
                    shown(source)
                );
            }
        }
    }
    for file in [TIMING, FIRMWARE] {
        assert!(seen.iter().any(|(f, _)| f == file), "{file} takes its board numbers from a generated block");
    }
    for name in README_SENTENCE_BLOCKS {
        assert!(
            sources.iter().any(|b| b.name == name),
            "{RESULTS} holds no generated block `{name}`: rerun `scripts/results.py`"
        );
        assert!(
            seen.iter().any(|(f, n)| f == "README.md" && n == name),
            "README.md states its `{name}` figures in the generated block `{name}`"
        );
    }
}

/// Up to 40 characters of `text` before byte `at`, on one line: the words a number follows.
fn before(text: &str, at: usize) -> String {
    let head: Vec<char> = text[..at].chars().collect();
    let words: String = head[head.len().saturating_sub(40)..].iter().collect();
    words.replace('\n', " ").trim().to_string()
}

/// Fails, at `at`, unless the block `ours` is the text of `docs/results.md`'s block `theirs`
/// (at line `line` there); names the first number that differs.
fn same_sentences(at: &str, ours: &str, theirs: &str, line: usize) {
    if ours == theirs {
        return;
    }
    let (a, b) = (numbers(ours), numbers(theirs));
    for (i, (n, pos)) in a.iter().enumerate() {
        let source = b.get(i).map(|(m, _)| m.as_str());
        assert_eq!(
            Some(n.as_str()),
            source,
            "{at}: states {n} (\"{}\"), where {RESULTS}:{line}'s block states {} (rerun \
             `scripts/results.py --blocks-only`, do not edit the block)",
            before(ours, *pos),
            shown(source)
        );
    }
    panic!(
        "{at}: is not the text of {RESULTS}:{line}'s block of the same name (rerun `scripts/results.py \
         --blocks-only`, do not edit the block):\n{ours}\n--- {RESULTS}:\n{theirs}"
    );
}

#[test]
fn board_numbers_are_stated_only_in_generated_blocks() {
    let (board, _) = results_board();
    let mut found = Vec::new();
    for file in documents() {
        let text = read(&file);
        let spans: Vec<_> = blocks(&file, &text).into_iter().map(|b| b.span).collect();
        for (number, at) in numbers(&text) {
            if spans.iter().any(|s| s.contains(&at)) {
                continue;
            }
            let line = line_of(&text, at);
            let integer: Option<u64> = number.replace(',', "").parse().ok();
            if let Some((quantity, _)) = board.iter().find(|(_, v)| *v == number && number.len() >= 4) {
                found.push(format!("{file}:{line}: {number} restates {RESULTS}'s {quantity} by hand"));
            } else if number.contains(',')
                && integer.is_some_and(|n| n >= 100_000)
                && !ALLOWED_LARGE.iter().any(|(n, _)| *n == number)
            {
                found.push(format!("{file}:{line}: {number}, a board count or size stated by hand"));
            } else if number.contains('.') && text[at + number.len()..].trim_start().starts_with("ms") {
                found.push(format!("{file}:{line}: {number} ms, a timing stated by hand"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "numbers outside the generated blocks (put them in a block scripts/results.py fills, or drop them):\n{}",
        found.join("\n")
    );
}

#[test]
fn walked_points_and_default_generations_are_the_codes() {
    let walked = SurfaceStrips::<DEFAULT_GRID>::WALKED_PER_CAMERA;
    let per_g = walked / DEFAULT_GRID;
    let firmware = read(FIRMWARE);
    let marker = " per camera, `SurfaceStrips::WALKED_PER_CAMERA`";
    let at = firmware.find(marker).unwrap_or_else(|| panic!("{FIRMWARE} states the walked points per camera"));
    let digits: String = firmware[..at].chars().rev().take_while(char::is_ascii_digit).collect();
    let stated: Option<usize> = digits.chars().rev().collect::<String>().parse().ok();
    assert_eq!(
        stated,
        Some(walked),
        "{FIRMWARE}:{}: states {} walked points per camera; the code's \
         SurfaceStrips::<{DEFAULT_GRID}>::WALKED_PER_CAMERA is {walked}",
        line_of(&firmware, at),
        shown(stated)
    );
    let timing = read(TIMING);
    let marker = "`SurfaceStrips::WALKED_PER_CAMERA` = ";
    let at = timing.find(marker).unwrap_or_else(|| panic!("{TIMING} states the walked points per camera"));
    let stated = leading_number(&timing[at + marker.len()..]);
    assert_eq!(
        stated,
        Some(per_g as u64),
        "{TIMING}:{}: states {}·G walked points per camera; the code's is {per_g}·G",
        line_of(&timing, at),
        shown(stated)
    );

    let default = u64::from(Tuning::DEFAULT.generations_per_frame);
    for file in documents() {
        let text = read(&file);
        for (at, _) in text.match_indices("generations_per_frame`") {
            let window: String = text[at..].chars().take(80).collect();
            let Some(d) = window.find("default ") else { continue };
            if let Some(n) = leading_number(&window[d + "default ".len()..]) {
                assert_eq!(
                    n,
                    default,
                    "{file}:{}: states generations_per_frame's default as {n}; Tuning::DEFAULT's is {default}",
                    line_of(&text, at)
                );
            }
        }
    }
    for file in [TIMING, FIRMWARE] {
        let lower = read(file).to_lowercase().replace('\n', " ");
        for phrase in ["one generation per frame", "one ga generation per frame"] {
            assert!(
                !lower.contains(phrase),
                "{file}: says \"{phrase}\"; a frame runs generations_per_frame generations (default {default})"
            );
        }
    }
}

#[test]
fn the_scanners_find_what_they_should() {
    let nums: Vec<String> = numbers("a 965,623 b, 12.81 ms, x1 2.").into_iter().map(|(n, _)| n).collect();
    assert_eq!(nums, ["965,623", "12.81", "2"]);
    assert_eq!(leading_number("(11) x"), Some(11));
    assert_eq!(leading_number(" (u8)"), None);
    let text = "a\n<!-- generated:x -->\n<!-- generated by scripts/results.py from the runs of commit abc; do not edit -->\n\
                | quantity | value |\n|---|---|\n| flash (B) | 1 |\n<!-- /generated -->\nb";
    let b = blocks("t", text);
    assert_eq!(b.len(), 1);
    assert_eq!((b[0].name.as_str(), b[0].line, b[0].stamp.as_deref()), ("x", 2, Some("abc")));
    assert_eq!(b[0].rows, [("flash (B)".to_string(), "1".to_string())]);
}

#[test]
#[should_panic(expected = "states 15.4")]
fn a_sentence_block_with_another_number_fails() {
    let theirs = "<!-- generated:x -->\n<!-- generated by scripts/results.py from the runs of commit abc; do not edit -->\n\
                  median RMS z 15.2 mm; 12.6 % wrong.\n<!-- /generated -->";
    same_sentences("t", theirs, theirs, 1);
    same_sentences("t", &theirs.replace("15.2", "15.4"), theirs, 1);
}
