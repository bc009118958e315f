//! Mutations: byte-level ones for any input, PLY header and ASCII token edits, `.spt`
//! header and record field edits. A few are stacked per input; `.spt` inputs are
//! usually resealed afterwards so that the edits reach past the checksum.

use spt::tree::spt_file::{HEADER_BYTES, reseal};

use crate::seeds::{Kind, Seed};

/// splitmix64: small, fast, and the same sequence on every machine.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (0 when n is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    pub fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Inputs never grow past this: every run stays short.
pub const MAX_LEN: usize = 1 << 16;

const INTERESTING_U64: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    0x7f,
    0x80,
    0xff,
    0x7fff,
    0x8000,
    0xffff,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    1 << 32,
    9_999_999_999,
    1_000_000_000_000_000_000,
    u64::MAX / 2,
    u64::MAX,
];
const INTERESTING_F64: &[f64] = &[
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    1e-320,
    1e-45,
    1e-7,
    1e7,
    1e10,
    1e18,
    3.4e38,
    1e36,
    1e300,
    -1e308,
    f64::MAX,
    f64::MIN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
];
const INTERESTING_TOKENS: &[&str] = &[
    "0",
    "-1",
    "1",
    "3",
    "255",
    "256",
    "65536",
    "4294967296",
    "-2147483649",
    "1e300",
    "-1e308",
    "3.4e38",
    "1e36",
    "1e10",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "0.5",
    "x",
    "",
];
const SCALAR_WORDS: &[&str] = &[
    "char",
    "uchar",
    "short",
    "ushort",
    "int",
    "uint",
    "float",
    "double",
    "int8",
    "uint8",
    "float32",
    "float64",
    "list uchar int",
    "list int float",
    "list uint uchar",
    "list float int",
];

/// Writes `v`'s low `width` bytes at `at` in either byte order.
fn put_int(b: &mut [u8], at: usize, width: usize, v: u64, big: bool) {
    let bytes = v.to_le_bytes();
    for k in 0..width.min(b.len().saturating_sub(at)) {
        b[at + k] = if big { bytes[width - 1 - k] } else { bytes[k] };
    }
}

fn put_float(b: &mut [u8], at: usize, wide: bool, v: f64, big: bool) {
    if wide {
        put_int(b, at, 8, v.to_bits(), big);
    } else {
        put_int(b, at, 4, (v as f32).to_bits() as u64, big);
    }
}

/// One byte-level mutation of `b`.
fn bytes_once(rng: &mut Rng, b: &mut Vec<u8>, seeds: &[Seed]) {
    let len = b.len();
    let at = rng.below(len);
    match rng.below(8) {
        0 if len > 0 => b[at] ^= 1 << rng.below(8),
        1 if len > 0 => b[at] = *rng.pick(&[0u8, 1, 0x7f, 0x80, 0xff, b' ', b'\n', b'-']),
        2 => {
            let width = *rng.pick(&[1, 2, 4, 8]);
            let v = *rng.pick(INTERESTING_U64);
            put_int(b, at, width, v, rng.chance(50));
        }
        3 => put_float(
            b,
            at,
            rng.chance(50),
            *rng.pick(INTERESTING_F64),
            rng.chance(50),
        ),
        4 => b.truncate(rng.below(len + 1)),
        5 if len > 0 => {
            let n = rng.below((len - at).min(64)) + 1;
            b.drain(at..at + n);
        }
        6 if len > 0 => {
            // A chunk of the input again, somewhere else.
            let n = rng.below((len - at).min(256)) + 1;
            let chunk = b[at..at + n].to_vec();
            let to = rng.below(len + 1);
            b.splice(to..to, chunk);
        }
        _ => {
            // Splice: this input's start, another seed's end.
            let other = &rng.pick(seeds).bytes;
            let from = rng.below(other.len() + 1);
            b.truncate(at);
            b.extend_from_slice(&other[from..]);
        }
    }
}

/// The PLY header's lines and the payload, or `None` without `end_header`.
fn split_header(b: &[u8]) -> Option<(Vec<String>, Vec<u8>)> {
    let end = b.windows(11).position(|w| w == b"end_header\n")? + 11;
    let text = String::from_utf8_lossy(&b[..end]);
    let lines = text.lines().map(str::to_owned).collect();
    Some((lines, b[end..].to_vec()))
}

/// One edit of the PLY header's lines: counts, types, lines removed, repeated,
/// swapped or added.
fn header_once(rng: &mut Rng, b: &mut Vec<u8>) {
    let Some((mut lines, payload)) = split_header(b) else {
        return;
    };
    let n = lines.len();
    if n < 3 {
        return;
    }
    // A line between `ply` and `end_header`.
    let i = 1 + rng.below(n - 2);
    match rng.below(7) {
        0 => {
            // A new count on an element line.
            if let Some(j) = (0..n)
                .map(|k| (i + k) % n)
                .find(|&k| lines[k].starts_with("element "))
            {
                let name = lines[j]
                    .split_whitespace()
                    .nth(1)
                    .unwrap_or("vertex")
                    .to_owned();
                let count = match rng.below(3) {
                    0 => rng.pick(INTERESTING_U64).to_string(),
                    1 => rng.pick(INTERESTING_TOKENS).to_string(),
                    _ => {
                        let old: i64 = lines[j]
                            .split_whitespace()
                            .nth(2)
                            .and_then(|c| c.parse().ok())
                            .unwrap_or(0);
                        (old + rng.below(5) as i64 - 2).to_string()
                    }
                };
                lines[j] = format!("element {name} {count}");
            }
        }
        1 => {
            // Another type for a property.
            if lines[i].starts_with("property ") {
                let name = lines[i].split_whitespace().last().unwrap_or("x").to_owned();
                lines[i] = format!("property {} {name}", rng.pick(SCALAR_WORDS));
            }
        }
        2 if n > 3 => {
            lines.remove(i);
        }
        3 => {
            let line = lines[i].clone();
            lines.insert(i, line);
        }
        4 => {
            let j = 1 + rng.below(n - 2);
            lines.swap(i, j);
        }
        5 => {
            let count = rng.pick(INTERESTING_U64);
            lines.insert(i, format!("element extra {count}"));
        }
        _ => {
            let format = rng.pick(&[
                "ascii",
                "binary_little_endian",
                "binary_big_endian",
                "binary",
            ]);
            lines[1] = format!("format {format} 1.0");
        }
    }
    let mut out = lines.join("\n").into_bytes();
    out.push(b'\n');
    out.extend_from_slice(&payload);
    *b = out;
}

/// Replaces one whitespace-separated token of an ASCII payload.
fn token_once(rng: &mut Rng, b: &mut Vec<u8>) {
    let Some(end) = b
        .windows(11)
        .position(|w| w == b"end_header\n")
        .map(|p| p + 11)
    else {
        return;
    };
    let starts: Vec<usize> = (end..b.len())
        .filter(|&k| !b[k].is_ascii_whitespace() && (k == end || b[k - 1].is_ascii_whitespace()))
        .collect();
    if starts.is_empty() {
        return;
    }
    let start = *rng.pick(&starts);
    let stop = (start..b.len())
        .find(|&k| b[k].is_ascii_whitespace())
        .unwrap_or(b.len());
    let token = rng.pick(INTERESTING_TOKENS).as_bytes().to_vec();
    b.splice(start..stop, token);
}

/// `.spt` header fields (offset, width, float?) worth editing one by one.
const SPT_FIELDS: &[(usize, usize, bool)] = &[
    (8, 4, false),
    (16, 4, false),
    (20, 4, false),
    (24, 8, false),
    (32, 8, false),
    (40, 8, true),
    (48, 8, true),
    (64, 8, true),
    (88, 8, true),
    (112, 4, true),
    (124, 4, true),
    (136, 4, true),
    (144, 8, false),
    (152, 8, false),
    (160, 8, false),
];

/// One edit of an `.spt` header field or of a field of one node record.
fn spt_once(rng: &mut Rng, b: &mut [u8]) {
    if b.len() < HEADER_BYTES {
        return;
    }
    if rng.chance(40) {
        let &(at, width, float) = rng.pick(SPT_FIELDS);
        if float {
            put_float(b, at, width == 8, *rng.pick(INTERESTING_F64), false);
        } else {
            put_int(b, at, width, *rng.pick(INTERESTING_U64), false);
        }
        return;
    }
    // A node record: position, radius (f32), normal, colour, errors, δ, level (u16).
    let records = (b.len() - HEADER_BYTES) / 36;
    if records == 0 {
        return;
    }
    let at = HEADER_BYTES + 32 * rng.below(records);
    let field = rng.below(8);
    match field {
        0..=3 => put_float(b, at + 4 * field, false, *rng.pick(INTERESTING_F64), false),
        4 => put_int(b, at + 16, 4, rng.next(), false),
        _ => {
            let half = *rng.pick(&[
                0u64, 1, 0x3c00, 0x7bff, 0x7c00, 0x7e00, 0x8001, 0xfc00, 0xffff,
            ]);
            put_int(b, at + 24 + 2 * (field - 5), 2, half, false);
        }
    }
}

/// A mutated copy of `seed`: one mutation of a kind that suits it (seven times in
/// ten; most inputs then still pass the header and reach deeper), else two to four.
pub fn mutate(rng: &mut Rng, seed: &Seed, seeds: &[Seed]) -> Vec<u8> {
    let mut b = seed.bytes.clone();
    let count = if rng.chance(70) { 1 } else { 2 + rng.below(3) };
    for _ in 0..count {
        match (seed.kind, rng.below(10)) {
            (Kind::Ply | Kind::Instances, 0..=2) => header_once(rng, &mut b),
            (Kind::Ply | Kind::Instances | Kind::Scene, 3..=4) => token_once(rng, &mut b),
            (Kind::Spt, 0..=5) => spt_once(rng, &mut b),
            _ => bytes_once(rng, &mut b, seeds),
        }
    }
    b.truncate(MAX_LEN);
    if seed.kind == Kind::Spt && rng.chance(90) {
        reseal(&mut b);
    }
    b
}
