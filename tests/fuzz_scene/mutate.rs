//! Structure-aware mutations of scene-file text for the scene-parser fuzz test.
//!
//! Hand-written rather than proptest/arbtest: the oracle needs to know, for each
//! mutation, whether it *must* make the file invalid (then loading it must fail)
//! or may leave it valid (then loading may succeed, but what it yields must be a
//! sane scene). A generic byte mutator cannot tell the two apart.
//!
//! A mutant is 0–2 "benign" mutations (any outcome allowed) followed, half the
//! time, by one "invalidating" mutation chosen so that no scene file in this
//! format can survive it whatever came before:
//! - appending a scalar to an array (no array of the format accepts one more
//!   scalar element: fixed-length number arrays, lists of rows, lists of tables);
//! - removing a number from an array (every number array has a fixed length);
//! - replacing a number by `nan`, `inf`, a string, a boolean or `[1]`;
//! - inserting an unknown key into a table or inline table (all are closed);
//! - a position, radius or camera coordinate of 1e13 (> `scene::MAX_MAGNITUDE`);
//! - a negative radius, a bogus `type`/`material`/`bump`/`file`/`integrator`;
//! - a duplicated key line.
#![allow(dead_code)]

/// splitmix64: tiny, seedable, good enough to pick mutations.
#[derive(Clone)]
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
    pub fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
}

/// What the oracle may accept for a mutant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// Loading may succeed or fail (no panic, no hang, sane result).
    Any,
    /// Loading must fail: the mutation made the file invalid.
    Reject,
}

pub struct Mutant {
    pub text: String,
    pub expect: Expect,
    /// The mutations applied, for the failure message.
    pub log: Vec<String>,
}

/// Where things are in a scene text (byte offsets), found by a small scanner
/// that skips comments and strings and tracks bracket depth.
#[derive(Default, Debug)]
struct Sites {
    /// Number tokens in value position: (start, end).
    numbers: Vec<(usize, usize)>,
    /// Numbers that are direct elements of an array: (start, end).
    array_numbers: Vec<(usize, usize)>,
    /// Byte offset of each value array's closing `]`.
    array_ends: Vec<usize>,
    /// Byte offset just after each inline table's `{`.
    inline_tables: Vec<usize>,
    /// Lines at depth 0 that hold `key = value` entirely: (line start, line end, key).
    key_lines: Vec<(usize, usize, String)>,
    /// Line starts at depth 0 (where a new key line may be inserted).
    line_starts: Vec<usize>,
    /// `key = "string"` values: (key, start of the string's content, end).
    strings: Vec<(String, usize, usize)>,
    /// Starts of `[[...]]` headers.
    block_starts: Vec<usize>,
}

fn is_token_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.' | b'+' | b'-')
}

fn scan(text: &str) -> Sites {
    let b = text.as_bytes();
    let mut s = Sites::default();
    // Stack of open brackets in value position: b'[' or b'{'.
    let mut stack: Vec<u8> = Vec::new();
    let mut i = 0;
    let mut line_start = 0;
    let mut in_value = false; // after `=` on this logical entry
    let mut key = String::new();
    let mut line_complete = true;
    while i < b.len() {
        let c = b[i];
        if c == b'\n' {
            if stack.is_empty() {
                if in_value && line_complete && !key.is_empty() {
                    s.key_lines.push((line_start, i + 1, key.clone()));
                }
                in_value = false;
                key.clear();
                line_complete = true;
                s.line_starts.push(i + 1);
            } else {
                line_complete = false;
            }
            if stack.is_empty() {
                line_start = i + 1;
            }
            i += 1;
            continue;
        }
        if c == b'#' {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        if c == b'"' || c == b'\'' {
            let q = c;
            let start = i + 1;
            i += 1;
            while i < b.len() && b[i] != q && b[i] != b'\n' {
                if q == b'"' && b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            if in_value && stack.is_empty() && !key.is_empty() {
                s.strings.push((key.clone(), start, i.min(b.len())));
            }
            i += 1;
            continue;
        }
        if !in_value && stack.is_empty() {
            // Key or header position.
            if c == b'[' && i == line_start {
                if b[i..].starts_with(b"[[") {
                    s.block_starts.push(i);
                }
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            if c == b'=' {
                in_value = true;
                key = text[line_start..i].trim().to_string();
            }
            i += 1;
            continue;
        }
        match c {
            b'[' => {
                stack.push(b'[');
                i += 1;
            }
            b'{' => {
                stack.push(b'{');
                s.inline_tables.push(i + 1);
                i += 1;
            }
            b']' | b'}' => {
                if c == b']' {
                    s.array_ends.push(i);
                }
                stack.pop();
                i += 1;
            }
            _ if is_token_char(c) => {
                let start = i;
                while i < b.len() && is_token_char(b[i]) {
                    i += 1;
                }
                let tok = &text[start..i];
                // A key inside an inline table is followed by `=`.
                let next = text[i..].trim_start().as_bytes().first().copied();
                let is_key = next == Some(b'=');
                let numeric = tok.replace('_', "").parse::<f64>().is_ok()
                    && tok.as_bytes()[0] != b'.'
                    && !tok.eq_ignore_ascii_case("infinity");
                if numeric && !is_key {
                    s.numbers.push((start, i));
                    if stack.last() == Some(&b'[') {
                        s.array_numbers.push((start, i));
                    }
                }
            }
            _ => i += 1,
        }
    }
    s
}

const GOOD_NUMBERS: &[&str] = &[
    "0", "1", "-1", "0.5", "2", "3", "1e-8", "100", "-3.7", "0.001", "1e6", "-1e6", "4096", "7",
    "0.25", "1e11", "-2e10", "1e-30", "180", "90", "-90", "65", "1.5",
];
const BAD_VALUES: &[&str] = &["nan", "inf", "-inf", "\"x\"", "true", "[1]", "+nan"];
const TYPE_NAMES: &[&str] = &[
    "sphere",
    "quad",
    "cube",
    "mesh",
    "rect",
    "lambert",
    "blinn_phong",
    "cook_torrance",
    "mirror",
    "constant",
    "image",
    "gaussian_sky",
    "sinusoids",
    "path",
    "direct",
];
/// Valid key lines that may fit some table (benign insertions).
const KEY_POOL: &[&str] = &[
    "radius = 0.3",
    "center = [0, 1, 0]",
    "emission = [1, 2, 3]",
    "size = [1, 2]",
    "transform = { rotate = [0, 1, 0, 30] }",
    "transform = { scale = [1, 2, 3], translate = [0, 1, 0] }",
    "transform = { matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]] }",
    "corner = [0, 0, 0]",
    "edge_u = [1, 0, 0]",
    "edge_v = [0, 0, 1]",
    "smooth_normals = true",
    "material = \"white\"",
    "radiance = [1, 1, 1]",
    "albedo = [0.5, 0.5, 0.5]",
    "exponent = 10",
    "up = [0, 0, 1]",
    "spp = 2",
    "max_depth = 1",
    "seed = 3",
    "rr_depth = 2",
    "scale = 2",
    "sharpness = 4",
    "peak = [1, 1, 1]",
    "name = \"n\"",
    "terms = [{ amplitude = 0.1, frequency = [1, 2] }]",
];
/// Keys whose value is a position, radius or camera coordinate: a component
/// of 1e13 always exceeds `scene::MAX_MAGNITUDE` (1e12).
const POSITION_KEYS: &[&str] = &["center", "corner", "from", "to", "translate", "radius"];
/// Keys whose string value must name something that exists.
const REFERENCE_KEYS: &[&str] = &["type", "material", "bump", "file", "integrator"];

fn splice(text: &str, start: usize, end: usize, with: &str) -> String {
    format!("{}{with}{}", &text[..start], &text[end..])
}

/// One benign mutation: the result may or may not be a valid file.
fn benign(text: &str, rng: &mut Rng) -> (String, String) {
    let s = scan(text);
    for _ in 0..8 {
        match rng.below(12) {
            0 | 1 if !s.numbers.is_empty() => {
                let &(a, b) = rng.pick(&s.numbers);
                let n = rng.pick(GOOD_NUMBERS);
                return (
                    splice(text, a, b, n),
                    format!("number {} -> {n}", &text[a..b]),
                );
            }
            2 if !s.key_lines.is_empty() => {
                let (a, b, k) = rng.pick(&s.key_lines).clone();
                return (splice(text, a, b, ""), format!("delete line `{k}`"));
            }
            3 if s.line_starts.len() > 1 => {
                let at = *rng.pick(&s.line_starts);
                let line = rng.pick(KEY_POOL);
                return (
                    splice(text, at, at, &format!("{line}\n")),
                    format!("insert `{line}`"),
                );
            }
            4 if !s.strings.is_empty() => {
                let (k, a, b) = rng.pick(&s.strings).clone();
                let t = rng.pick(TYPE_NAMES);
                return (splice(text, a, b, t), format!("{k} = \"{t}\""));
            }
            5 if !s.block_starts.is_empty() => {
                let i = rng.below(s.block_starts.len());
                let a = s.block_starts[i];
                let b = s.block_starts.get(i + 1).copied().unwrap_or(text.len());
                let block = text[a..b].to_string();
                let sep = if block.ends_with('\n') { "" } else { "\n" };
                return (
                    format!("{text}{sep}{block}"),
                    format!("duplicate block at {a}"),
                );
            }
            6 if s.key_lines.len() > 1 => {
                // Move a key line elsewhere (possibly into another table).
                let (a, b, k) = rng.pick(&s.key_lines).clone();
                let line = text[a..b].to_string();
                let rest = splice(text, a, b, "");
                let starts = scan(&rest).line_starts;
                if let Some(&at) = starts.get(rng.below(starts.len().max(1))) {
                    return (splice(&rest, at, at, &line), format!("move `{k}`"));
                }
            }
            7..=9 if !text.is_empty() => {
                // Character-level noise.
                let mut at = rng.below(text.len());
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                let noise = [
                    "", "\"", "[", "]", "{", "}", ",", "=", "\n", "1", "-", ".", "φ", "#", " ",
                ];
                let with = *rng.pick(&noise);
                let mut end = at;
                if rng.chance(2) && at < text.len() {
                    end = at + 1;
                    while !text.is_char_boundary(end) {
                        end += 1;
                    }
                }
                return (
                    splice(text, at, end, with),
                    format!("noise at {at}: {with:?}"),
                );
            }
            10 if text.len() > 1 => {
                let mut at = rng.below(text.len());
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                return (text[..at].to_string(), format!("truncate at {at}"));
            }
            11 if !s.numbers.is_empty() => {
                // A number far outside any sensible range (f32 overflow or underflow).
                let &(a, b) = rng.pick(&s.numbers);
                let n = rng.pick(&[
                    "1e39",
                    "-1e39",
                    "1e-46",
                    "3e38",
                    "123456789012",
                    "4294967296",
                ]);
                return (
                    splice(text, a, b, n),
                    format!("number {} -> {n}", &text[a..b]),
                );
            }
            _ => {}
        }
    }
    (text.to_string(), "none".into())
}

/// One mutation that no valid file survives; `None` when the text offers no site
/// for the chosen kind.
fn invalidating(text: &str, rng: &mut Rng) -> Option<(String, String)> {
    let s = scan(text);
    match rng.below(9) {
        0 => {
            let &end = s.array_ends.get(rng.below(s.array_ends.len().max(1)))?;
            let before = text[..end].trim_end();
            let extra = rng.pick(&["9", "\"x\"", "nan", "0.8"]);
            let insert = if before.ends_with('[') || before.ends_with(',') {
                format!(" {extra}")
            } else {
                format!(", {extra}")
            };
            let at = before.len();
            Some((
                splice(text, at, at, &insert),
                format!("append {extra} at {at}"),
            ))
        }
        1 => {
            let &(a, b) = s
                .array_numbers
                .get(rng.below(s.array_numbers.len().max(1)))?;
            // Remove the number and one adjacent comma.
            let after = &text[b..];
            let trimmed = after.trim_start();
            let (start, end) = if trimmed.starts_with(',') {
                (a, b + (after.len() - trimmed.len()) + 1)
            } else {
                let before = text[..a].trim_end();
                if before.ends_with(',') {
                    (before.len() - 1, b)
                } else {
                    (a, b)
                }
            };
            Some((
                splice(text, start, end, ""),
                format!("remove {}", &text[a..b]),
            ))
        }
        2 => {
            let &(a, b) = s.numbers.get(rng.below(s.numbers.len().max(1)))?;
            let v = rng.pick(BAD_VALUES);
            Some((
                splice(text, a, b, v),
                format!("number {} -> {v}", &text[a..b]),
            ))
        }
        3 => {
            let &at = s.line_starts.get(rng.below(s.line_starts.len().max(1)))?;
            Some((
                splice(text, at, at, "zzz_unknown = 1\n"),
                format!("unknown key at {at}"),
            ))
        }
        4 => {
            let &at = s
                .inline_tables
                .get(rng.below(s.inline_tables.len().max(1)))?;
            Some((
                splice(text, at, at, " zzz_unknown = 1,"),
                format!("unknown inline key at {at}"),
            ))
        }
        5 => {
            // A position/radius/camera coordinate beyond the magnitude limit.
            let lines: Vec<_> = s
                .key_lines
                .iter()
                .filter(|(_, _, k)| POSITION_KEYS.contains(&k.as_str()))
                .collect();
            let &&(a, b, ref k) = lines.get(rng.below(lines.len().max(1)))?;
            let nums: Vec<_> = s
                .numbers
                .iter()
                .filter(|(x, _)| *x >= a && *x < b)
                .collect();
            let &&(x, y) = nums.get(rng.below(nums.len().max(1)))?;
            Some((
                splice(text, x, y, "1e13"),
                format!("{k}: {} -> 1e13", &text[x..y]),
            ))
        }
        6 => {
            let lines: Vec<_> = s
                .key_lines
                .iter()
                .filter(|(_, _, k)| k == "radius")
                .collect();
            let &&(a, b, _) = lines.get(rng.below(lines.len().max(1)))?;
            Some((
                splice(text, a, b, "radius = -0.5\n"),
                "radius = -0.5".into(),
            ))
        }
        7 => {
            let refs: Vec<_> = s
                .strings
                .iter()
                .filter(|(k, _, _)| REFERENCE_KEYS.contains(&k.as_str()))
                .collect();
            let &&(ref k, a, b) = refs.get(rng.below(refs.len().max(1)))?;
            Some((
                splice(text, a, b, "bogus_zz"),
                format!("{k} = \"bogus_zz\""),
            ))
        }
        _ => {
            let lines: Vec<_> = s.key_lines.iter().filter(|(a, b, _)| b > a).collect();
            let &&(a, b, ref k) = lines.get(rng.below(lines.len().max(1)))?;
            let line = text[a..b].to_string();
            Some((splice(text, b, b, &line), format!("duplicate key `{k}`")))
        }
    }
}

/// A mutant of `base`: 0–2 benign mutations, then (half the time) one
/// invalidating mutation.
pub fn mutate(base: &str, rng: &mut Rng) -> Mutant {
    let mut text = base.to_string();
    let mut log = Vec::new();
    for _ in 0..rng.below(3) {
        let (t, what) = benign(&text, rng);
        text = t;
        log.push(what);
    }
    let mut expect = Expect::Any;
    if rng.chance(2) {
        for _ in 0..4 {
            if let Some((t, what)) = invalidating(&text, rng) {
                text = t;
                log.push(format!("[invalidating] {what}"));
                expect = Expect::Reject;
                break;
            }
        }
    }
    Mutant { text, expect, log }
}

/// Only benign mutations (1–3): for the old-vs-new differential check, where
/// every mutant is loaded by both parsers.
pub fn mutate_benign(base: &str, rng: &mut Rng) -> Mutant {
    let mut text = base.to_string();
    let mut log = Vec::new();
    for _ in 0..1 + rng.below(3) {
        let (t, what) = benign(&text, rng);
        text = t;
        log.push(what);
    }
    Mutant {
        text,
        expect: Expect::Any,
        log,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scanner_finds_values_not_comments_or_keys() {
        let t = "# 12 in a comment\n[camera]\nfrom = [0, 1.5, -2] # 7\nname = \"a 3 b\"\nt = { scale = 2, k2 = 3 }\n";
        let s = scan(t);
        let nums: Vec<&str> = s.numbers.iter().map(|&(a, b)| &t[a..b]).collect();
        assert_eq!(nums, ["0", "1.5", "-2", "2", "3"]);
        assert_eq!(s.array_numbers.len(), 3);
        assert_eq!(s.key_lines.len(), 3);
        assert_eq!(s.strings.len(), 1);
    }
}
