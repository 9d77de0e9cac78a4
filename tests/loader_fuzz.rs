//! Mutated course scenes never make `parse` panic: bytes flipped, elements
//! deleted or duplicated, numbers replaced by huge, negative or non-finite
//! values, text truncated. Fixed seed and case counts keep runs repeatable.

use crate::common;

use ember::scene::collada::parse;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::ops::Range;
use std::sync::LazyLock;

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");

/// Values that stress counts, indices, offsets and transforms.
const NASTY_NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "-0",
    "1e30",
    "-1e30",
    "1e39",
    "1e-45",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "2147483647",
    "255",
    "3.5",
];

/// A seed document with the byte ranges of its elements, for structural edits.
struct Seed {
    name: &'static str,
    text: String,
    elements: Vec<Range<usize>>,
}

fn seed(name: &'static str, text: String) -> Seed {
    let doc = roxmltree::Document::parse(&text).expect(name);
    let elements = doc
        .descendants()
        .filter(|n| n.is_element() && n.parent_element().is_some())
        .map(|n| n.range())
        .collect();
    Seed {
        name,
        text,
        elements,
    }
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(format!("{SCENES}/{rel}")).expect(rel)
}

static SMALL: LazyLock<Vec<Seed>> = LazyLock::new(|| {
    vec![
        seed("CBspheres", read("cs184/sky/CBspheres.dae")),
        seed("CBempty", read("cs184/sky/CBempty.dae")),
        seed("CBgems", read("cs184/sky/CBgems.dae")),
        seed("sphere7_glass", read("cmu462/basic/sphere7_glass.dae")),
        seed("template", common::TEMPLATE.to_string()),
    ]
});

static LARGE: LazyLock<Vec<Seed>> =
    LazyLock::new(|| vec![seed("CBbunny", read("cs184/sky/CBbunny.dae"))]);

/// Byte ranges of number-like tokens (digits with sign, point, exponent).
fn number_tokens(text: &str) -> Vec<Range<usize>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            let start = i;
            i += 1;
            while i < b.len() && matches!(b[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+') {
                i += 1;
            }
            out.push(start..i);
        } else {
            i += 1;
        }
    }
    out
}

#[derive(Clone, Debug)]
enum Edit {
    DeleteElement(usize),
    DuplicateElement(usize),
    ReplaceNumber(usize, usize),
    FlipByte(usize, u8),
    Truncate(usize),
}

fn edit_strategy() -> impl Strategy<Value = Edit> {
    prop_oneof![
        2 => any::<usize>().prop_map(Edit::DeleteElement),
        2 => any::<usize>().prop_map(Edit::DuplicateElement),
        4 => (any::<usize>(), 0..NASTY_NUMBERS.len()).prop_map(|(i, v)| Edit::ReplaceNumber(i, v)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::FlipByte(i, b)),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ]
}

/// Applies `edits` in order. Element edits use the seed's original ranges,
/// so they are applied only while the text is still the seed's.
fn mutate(seed: &Seed, edits: &[Edit]) -> String {
    let mut bytes = seed.text.as_bytes().to_vec();
    let mut pristine = true;
    for e in edits {
        match *e {
            Edit::DeleteElement(i) if pristine => {
                let r = seed.elements[i % seed.elements.len()].clone();
                bytes.drain(r);
            }
            Edit::DuplicateElement(i) if pristine => {
                let r = seed.elements[i % seed.elements.len()].clone();
                let copy = bytes[r.clone()].to_vec();
                bytes.splice(r.end..r.end, copy);
            }
            Edit::DeleteElement(_) | Edit::DuplicateElement(_) => continue,
            Edit::ReplaceNumber(i, v) => {
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let tokens = number_tokens(&text);
                if tokens.is_empty() {
                    continue;
                }
                let r = tokens[i % tokens.len()].clone();
                let mut t = text.into_bytes();
                t.splice(r, NASTY_NUMBERS[v].bytes());
                bytes = t;
            }
            Edit::FlipByte(i, b) => {
                if !bytes.is_empty() {
                    let k = i % bytes.len();
                    bytes[k] = b;
                }
            }
            Edit::Truncate(i) => {
                let k = i % (bytes.len() + 1);
                bytes.truncate(k);
            }
        }
        pristine = false;
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// `parse` must return (either way) and an error must be one line naming the file.
fn check(text: &str) -> Result<(), TestCaseError> {
    if let Err(e) = parse(text, "fuzz.dae") {
        let msg = e.to_string();
        prop_assert!(msg.starts_with("fuzz.dae: "), "{}", msg);
        prop_assert!(!msg.contains('\n'), "{}", msg);
    }
    Ok(())
}

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config(4000, 0x0ddba11))]

    #[test]
    fn mutated_small_scenes_never_panic(
        which in 0..5usize,
        edits in prop::collection::vec(edit_strategy(), 1..6),
    ) {
        let s = &SMALL[which];
        let text = mutate(s, &edits);
        check(&text).map_err(|e| TestCaseError::fail(format!("{}: {e}", s.name)))?;
    }
}

proptest! {
    #![proptest_config(config(48, 0xb0b))]

    #[test]
    fn mutated_large_scene_never_panics(
        edits in prop::collection::vec(edit_strategy(), 1..4),
    ) {
        check(&mutate(&LARGE[0], &edits))?;
    }
}

proptest! {
    #![proptest_config(config(600, 0x5eed))]

    /// Every number of a small file replaced at once by the same nasty value.
    #[test]
    fn all_numbers_nasty(which in 0..5usize, v in 0..NASTY_NUMBERS.len(), keep in 0..4usize) {
        let s = &SMALL[which];
        let tokens = number_tokens(&s.text);
        let mut out = String::new();
        let mut last = 0;
        for (k, r) in tokens.iter().enumerate() {
            // Keep some numbers so that not everything fails at the first one.
            if k % 4 == keep { continue; }
            out.push_str(&s.text[last..r.start]);
            out.push_str(NASTY_NUMBERS[v]);
            last = r.end;
        }
        out.push_str(&s.text[last..]);
        check(&out)?;
    }
}
