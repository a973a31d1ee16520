//! Names as robot languages compare them, for every dialect: ASCII case-insensitive, blanks
//! ignored (`pArr{ 2 }` is `PARR{2}`, `p[ 3 ]` is `P[3]`), and one fast hasher for the maps
//! keyed by them.

use std::cell::Cell;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use hashbrown::hash_table::{Entry, HashTable};

const K: u64 = 0x51_7c_c1_b7_27_22_0a_95;

/// Names are short, trusted-enough keys (the file is the user's own program) and a module holds
/// hundreds of thousands of them: SipHash showed up as a tenth of the run time. This is the
/// multiply-rotate hash of rustc's `FxHasher` with a finaliser, written out to avoid a
/// dependency.
#[derive(Default, Clone, Copy)]
pub(crate) struct NameHasher(u64);

impl Hasher for NameHasher {
    /// Eight bytes a step, little-endian, the last word zero-padded. The padded word is
    /// shifted together here: copying a short tail into a zeroed array was a `memcpy` call
    /// per hash, a fifth of the cost of looking a short name up.
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            let word = <[u8; 8]>::try_from(w).map_or(0, u64::from_le_bytes);
            self.0 = mix(self.0, word);
        }
        let tail = words.remainder();
        if !tail.is_empty() {
            let word = tail.iter().rev().fold(0, |w, &b| w << 8 | u64::from(b));
            self.0 = mix(self.0, word);
        }
    }

    /// As [`write`](Self::write) of its eight bytes (little-endian).
    fn write_u64(&mut self, n: u64) {
        self.0 = mix(self.0, n);
    }

    fn write_u8(&mut self, b: u8) {
        self.0 = (self.0.rotate_left(5) ^ u64::from(b)).wrapping_mul(K);
    }

    fn write_usize(&mut self, n: usize) {
        self.0 = (self.0.rotate_left(5) ^ n as u64).wrapping_mul(K);
    }

    /// MurmurHash3's finaliser: hashbrown picks buckets from the low bits, which the
    /// multiply alone leaves equal for names differing only in their last bytes (`XP100001`).
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

/// One step of [`NameHasher`]: a word into the state.
#[inline(always)]
fn mix(state: u64, word: u64) -> u64 {
    (state.rotate_left(5) ^ word).wrapping_mul(K)
}

/// A map keyed by names, with [`NameHasher`].
pub(crate) type NameMap<K, V> = HashMap<K, V, BuildHasherDefault<NameHasher>>;

/// A name in the source, compared as the languages compare names. Borrows the source: no copy
/// per declaration or use.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NameKey<'s>(pub &'s [u8]);

impl NameKey<'_> {
    /// The folded bytes: upper case, blanks dropped.
    fn bytes(&self) -> impl Iterator<Item = u8> + '_ {
        self.0
            .iter()
            .filter(|b| !b.is_ascii_whitespace())
            .map(u8::to_ascii_uppercase)
    }

    /// The name is `word` (any case). A name without blanks folds to its bytes upper-cased:
    /// its bytes are compared, lengths first (`tGun` is not `tool0`), not folded one by one.
    #[inline]
    pub(crate) fn is(&self, word: &[u8]) -> bool {
        if self.differs_at_once(word) {
            return false;
        }
        if !self.0.iter().any(u8::is_ascii_whitespace) {
            return self.0.eq_ignore_ascii_case(word);
        }
        self.bytes().eq(word.iter().map(u8::to_ascii_uppercase))
    }

    /// The name starts with `prefix` (any case).
    pub(crate) fn starts_with(&self, prefix: &[u8]) -> bool {
        if self.differs_at_once(prefix) {
            return false;
        }
        let mut b = self.bytes();
        prefix
            .iter()
            .all(|&l| b.next() == Some(l.to_ascii_uppercase()))
    }

    /// Whether the name's first byte, not a blank (folding drops blanks), is another letter
    /// than `word`'s: most names asked about (every argument of every call, against `tool0`
    /// and a motion's prefixes) are told apart there, without folding either.
    #[inline]
    fn differs_at_once(&self, word: &[u8]) -> bool {
        match (self.0.first(), word.first()) {
            (Some(a), Some(b)) => !a.is_ascii_whitespace() && !a.eq_ignore_ascii_case(b),
            _ => false,
        }
    }

    /// `z10`, `v1000`: the prefix letter then digits only.
    pub(crate) fn numbered(&self, prefix: u8) -> bool {
        let mut b = self.bytes();
        b.next() == Some(prefix.to_ascii_uppercase()) && {
            let mut digits = 0;
            b.all(|c| {
                digits += 1;
                c.is_ascii_digit()
            }) && digits > 0
        }
    }
}

impl std::hash::Hash for NameKey<'_> {
    /// [`hash_of`] the folded bytes, written as one number: a word at a time for a short name
    /// ([`ShortKey`]), else the folded bytes gathered into the words [`NameHasher::write`]
    /// takes. Writing each folded byte was a fifth of finding a module's duplicate names.
    fn hash<H: Hasher>(&self, state: &mut H) {
        let hash = match ShortKey::of(self.0, false) {
            Some(short) => short.hash(),
            None => {
                let mut h = NameHasher::default();
                let (mut word, mut n) = (0u64, 0);
                for b in self.bytes() {
                    word |= u64::from(b) << (8 * n);
                    n += 1;
                    if n == 8 {
                        h.0 = mix(h.0, word);
                        (word, n) = (0, 0);
                    }
                }
                if n > 0 {
                    h.0 = mix(h.0, word);
                }
                h.finish()
            }
        };
        state.write_u64(hash);
    }
}

impl PartialEq for NameKey<'_> {
    fn eq(&self, other: &Self) -> bool {
        // Names are almost always written the same way twice: compare bytes first.
        self.0 == other.0 || self.bytes().eq(other.bytes())
    }
}

impl Eq for NameKey<'_> {}

/// The owned key of a name: its [`NameKey`] bytes as text (`p[ 3 ]` → `P[3]`).
pub(crate) fn fold(name: &str) -> String {
    let mut key = String::with_capacity(name.len());
    fold_str_into(&mut key, name);
    key
}

/// [`fold`] of `name` into a reused buffer.
fn fold_str_into<'b>(buf: &'b mut String, name: &str) -> &'b str {
    buf.clear();
    buf.extend(
        name.chars()
            .filter(|c| !c.is_ascii_whitespace())
            .map(|c| c.to_ascii_uppercase()),
    );
    buf
}

/// [`fold`] of a name's UTF-8 bytes into a reused buffer, byte by byte: only ASCII bytes
/// change (or go), so every character's bytes stay whole, and pushing a byte is cheaper than
/// pushing a character (which was most of indexing a module's target names).
fn fold_utf8_into<'b>(buf: &'b mut Vec<u8>, name: &[u8]) -> &'b [u8] {
    buf.clear();
    buf.extend(
        name.iter()
            .filter(|b| !b.is_ascii_whitespace())
            .map(u8::to_ascii_uppercase),
    );
    buf
}

/// [`fold`] of source bytes (Latin-1) into a reused buffer.
pub(crate) fn fold_into<'b>(buf: &'b mut String, bytes: &[u8]) -> &'b str {
    buf.clear();
    buf.extend(
        bytes
            .iter()
            .filter(|b| !b.is_ascii_whitespace())
            .map(|&b| (b as char).to_ascii_uppercase()),
    );
    buf
}

/// The longest reference [`NameIndex::exact_else_elements_raw`] folds on the stack.
const RAW_KEY: usize = 32;

/// [`fold`] of source bytes (Latin-1) that are ASCII without blanks, as nearly every reference
/// is (`p10`, `pArr{3}`): each byte upper-cased, into `key`. `None` for any other bytes, or
/// more than `key` holds.
fn fold_ascii_into<'k>(key: &'k mut [u8; RAW_KEY], raw: &[u8]) -> Option<&'k [u8]> {
    let key = key.get_mut(..raw.len())?;
    let mut plain = true;
    for (k, &b) in key.iter_mut().zip(raw) {
        plain &= b.is_ascii() && !b.is_ascii_whitespace();
        *k = b.to_ascii_uppercase();
    }
    plain.then_some(key)
}

/// One to eight bytes as a little-endian word, zero-padded, read in two reads that may
/// overlap (their common bytes are alike, so or-ing them places each once), not one at a
/// time: three places for one to three bytes (the first, middle and last), two halves of four
/// bytes for four to eight. `None` for no bytes or more than eight.
#[inline]
fn short_word(bytes: &[u8]) -> Option<u64> {
    let len = bytes.len();
    let at = |i: usize| bytes.get(i).map_or(0, |&b| u64::from(b)) << (8 * i);
    let half = |i: usize| {
        let four = bytes
            .get(i..i + 4)
            .and_then(|b| <[u8; 4]>::try_from(b).ok());
        four.map_or(0, |b| u64::from(u32::from_le_bytes(b))) << (8 * i)
    };
    match len {
        1..=3 => Some(at(0) | at(len / 2) | at(len - 1)),
        4..=8 => Some(half(0) | half(len - 4)),
        _ => None,
    }
}

/// Whether `a` and `b` are the same bytes: for eight bytes or fewer, as two words, where
/// comparing slices is a call (`memcmp`) per compare of a call's tool or work object with the
/// one before.
#[inline]
pub(crate) fn same_bytes(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len()
        && match (short_word(a), short_word(b)) {
            (Some(x), Some(y)) => x == y,
            _ => a == b,
        }
}

/// A folded name of one to eight bytes, as the word [`NameHasher::write`] makes of it: its
/// bytes little-endian, zero-padded. Nearly every name is that short (`p10`, `pArr{3}`), and
/// folding and hashing it a word at a time is a few operations, where a byte at a time was
/// most of looking a reference up and of indexing a declaration.
#[derive(Clone, Copy)]
struct ShortKey {
    word: u64,
    len: usize,
}

/// Each byte of a word 1; bit 7 of each byte; the other seven bits of each byte.
const LOW: u64 = 0x0101_0101_0101_0101;
const HIGH: u64 = 0x80 * LOW;
const SEVEN: u64 = 0x7F * LOW;

impl ShortKey {
    /// The folded `bytes` (a name's UTF-8 bytes, or with `ascii` a source's Latin-1 bytes),
    /// when they are one to eight bytes, none below 0x21 (no blank, nor a control character)
    /// nor, with `ascii`, beyond ASCII: upper-casing each then folds them. `None` otherwise.
    fn of(bytes: &[u8], ascii: bool) -> Option<ShortKey> {
        let len = bytes.len();
        let word = short_word(bytes)?;
        let mask = u64::MAX >> (64 - 8 * len);
        // Bit 7 of a byte below 0x21 is set in the word less 0x21 each (a borrow reaches a
        // byte only from one below it that is itself below 0x21; a byte with bit 7 set
        // is none).
        let below = word.wrapping_sub(0x21 * LOW) & !word & HIGH & mask;
        let beyond = word & HIGH;
        if below != 0 || (ascii && beyond != 0) {
            return None;
        }
        // A byte from `a` to `z` is one without bit 7 whose low seven bits set it when 0x1F
        // is added but not when 0x05 is (no sum carries into the next byte).
        let heptets = word & SEVEN;
        let lower = (heptets + 0x1F * LOW) & !(heptets + 0x05 * LOW) & !word & HIGH;
        Some(ShortKey {
            word: word - (lower >> 2),
            len,
        })
    }

    /// [`hash_of`] the folded bytes: the one word [`NameHasher::write`] mixes.
    fn hash(self) -> u64 {
        NameHasher(mix(NameHasher::default().0, self.word)).finish()
    }
}

/// The first characters of a set of names as [`fold`] compares them: a reference that starts
/// with none of them folds to none of the names (nor to an element of one), and need not be
/// folded and looked up. A module's motions pass `v1000, z10, tGun` beside their target `p10`,
/// and asking a hash set whether each was already missed was a tenth of binding them.
pub(crate) struct FirstLetters {
    /// By source byte (Latin-1, either case).
    bytes: [bool; 256],
    /// A name folds to nothing.
    empty: bool,
}

impl FirstLetters {
    pub(crate) fn new() -> FirstLetters {
        FirstLetters {
            bytes: [false; 256],
            empty: false,
        }
    }

    /// [`insert`](Self::insert) of a name's UTF-8 bytes: an ASCII first character is its
    /// byte, any other is decoded.
    #[inline]
    pub(crate) fn insert_utf8(&mut self, name: &[u8]) {
        match name.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(&b) if b.is_ascii() => self.mark(b),
            Some(_) => self.insert(&String::from_utf8_lossy(name)),
            None => self.empty = true,
        }
    }

    /// Adds the first character of `name` past blanks (folding drops them). A character
    /// beyond Latin-1 is no byte of a source: nothing is marked for it.
    pub(crate) fn insert(&mut self, name: &str) {
        match name.chars().find(|c| !c.is_ascii_whitespace()) {
            Some(c) => {
                if let Ok(b) = u8::try_from(u32::from(c)) {
                    self.mark(b);
                }
            }
            None => self.empty = true,
        }
    }

    fn mark(&mut self, b: u8) {
        self.bytes[usize::from(b.to_ascii_uppercase())] = true;
        self.bytes[usize::from(b.to_ascii_lowercase())] = true;
    }

    /// Whether source bytes `raw` may fold to a name whose first character was inserted.
    pub(crate) fn may_start(&self, raw: &[u8]) -> bool {
        match raw.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(&b) => self.bytes[usize::from(b)],
            None => self.empty,
        }
    }
}

/// Declared names of a program, folded, with the elements of each array under the array's name:
/// what both languages' usage resolvers look a motion's references up in. `T` says where the
/// declaration is (an index into a file's positions, …). Built once with [`NameIndexBuilder`],
/// then only read.
///
/// A 20 MB module declares 100,000 targets: a map of `String` keys to a vector each held
/// 170 bytes and three heap blocks per name (a tenth of `check`'s peak memory, and its
/// allocations a sixth of the time). Here every folded name is one run of a shared text, the
/// declarations are grouped in one list, and a hash table of `u32` finds a name's group: about
/// 40 bytes per name and no block of its own.
pub(crate) struct NameIndex<T> {
    /// The bracket that opens an array index (`{` in RAPID, `[` in KRL).
    open: u8,
    exact: Groups<T>,
    elements: Groups<T>,
}

/// Collects a [`NameIndex`]'s declarations; [`NameIndexBuilder::build`] groups them.
pub(crate) struct NameIndexBuilder<T> {
    open: u8,
    buf: Vec<u8>,
    exact: Groups<T>,
    elements: Groups<T>,
    /// (group, declaration) of every insertion into `exact`, in order; likewise `in_arrays`.
    in_exact: Vec<(u32, T)>,
    in_arrays: Vec<(u32, T)>,
}

/// Distinct folded names, each with the declarations made under it (in insertion order).
struct Groups<T> {
    /// The folded names' UTF-8 bytes, one after another.
    text: Vec<u8>,
    /// Each name's range of `text`.
    names: Vec<(u32, u32)>,
    /// Name `k` as `k`, hashed by its text: the names are in `text`, so the table holds
    /// four bytes a name.
    table: HashTable<u32>,
    /// Name `k`'s declarations are `values[ends[k - 1]..ends[k]]` (`0..ends[0]` for the first),
    /// or `values[k..k + 1]` when `one_each`.
    ends: Vec<u32>,
    values: Vec<T>,
    /// Every name was declared once (a module's targets, nearly always): name `k` is the
    /// `k`-th insertion, and neither `ends` nor a sorted copy of the insertions is made.
    one_each: bool,
    /// The name after the one [`get_hashed`](Groups::get_hashed) found last, tried before the
    /// table, and then that one again. A program's motions mostly name its targets in the order
    /// they are declared, some twice in a row (`MoveL Offs(p10, 0, 0, 100), …` before
    /// `MoveL p10, …`), and the names are grouped in that order: a guess then reads the entries
    /// at or just past the last ones, where the table's probe and the entries it leads to were
    /// a cache miss each (a 20 MB module's 100,000 names are 4 MB of them; these lookups were
    /// 6-11 % of its `check`, with 1.5 % of the instructions). A guess is a name compared,
    /// never a different answer: each name is one group.
    next: Cell<u32>,
}

fn hash_of(key: &[u8]) -> u64 {
    let mut h = NameHasher::default();
    h.write(key);
    h.finish()
}

/// Name `k` of `text` and `names` (a free function: the table's closures borrow these two
/// fields while the table itself is borrowed mutably).
fn name_in<'t>(text: &'t [u8], names: &[(u32, u32)], k: u32) -> &'t [u8] {
    names
        .get(k as usize)
        .and_then(|&(s, e)| text.get(s as usize..e as usize))
        .unwrap_or_default()
}

impl<T: Copy> Groups<T> {
    fn with_capacity(n: usize) -> Groups<T> {
        Groups {
            text: Vec::new(),
            names: Vec::with_capacity(n),
            table: HashTable::with_capacity(n),
            ends: Vec::new(),
            values: Vec::new(),
            one_each: false,
            next: Cell::new(0),
        }
    }

    /// The group of `key`, added if new.
    fn intern(&mut self, key: &[u8]) -> u32 {
        self.intern_hashed(key, hash_of(key))
    }

    /// [`Groups::intern`] of `key` hashed as `hash`.
    fn intern_hashed(&mut self, key: &[u8], hash: u64) -> u32 {
        let Groups {
            text, names, table, ..
        } = self;
        match table.entry(
            hash,
            |&k| same_bytes(name_in(text, names, k), key),
            |&k| hash_of(name_in(text, names, k)),
        ) {
            Entry::Occupied(e) => *e.get(),
            Entry::Vacant(e) => {
                let k = names.len() as u32;
                let start = text.len() as u32;
                text.extend_from_slice(key);
                names.push((start, text.len() as u32));
                e.insert(k);
                k
            }
        }
    }

    /// Places the declarations, grouped by name and in insertion order within a group (a
    /// counting sort: no comparison of names).
    fn fill(&mut self, inserted: Vec<(u32, T)>) {
        self.text.shrink_to_fit();
        self.names.shrink_to_fit();
        if inserted.len() == self.names.len() {
            // Each insertion made a name, numbered in the order inserted: the insertions are
            // the groups, in place (the vector is reused for the values). The counting sort's
            // three vectors were 2 MB of fresh pages for a 20 MB module's 100,000 targets.
            debug_assert!(
                inserted
                    .iter()
                    .enumerate()
                    .all(|(k, &(g, _))| g as usize == k)
            );
            self.values = inserted.into_iter().map(|(_, at)| at).collect();
            self.one_each = true;
            return;
        }
        let mut ends = vec![0u32; self.names.len()];
        for &(k, _) in &inserted {
            if let Some(e) = ends.get_mut(k as usize) {
                *e += 1;
            }
        }
        let mut total = 0;
        for e in ends.iter_mut() {
            total += *e;
            *e = total;
        }
        // Filled from the back, so each group's values come out in insertion order. (No
        // insertion is no name, which the case above took.)
        let Some(&(_, any)) = inserted.first() else {
            return;
        };
        let mut values = vec![any; inserted.len()];
        let mut next = ends.clone();
        for &(k, at) in inserted.iter().rev() {
            if let Some(n) = next.get_mut(k as usize) {
                *n -= 1;
                if let Some(v) = values.get_mut(*n as usize) {
                    *v = at;
                }
            }
        }
        self.ends = ends;
        self.values = values;
    }

    fn get(&self, key: &[u8]) -> &[T] {
        // Most programs declare no array: the empty table needs no hash.
        if self.names.is_empty() {
            return &[];
        }
        self.get_hashed(key, hash_of(key))
    }

    /// [`Groups::get`] of `key` hashed as `hash`.
    fn get_hashed(&self, key: &[u8], hash: u64) -> &[T] {
        let next = self.next.get();
        let is = |k: u32| {
            (k as usize) < self.names.len() && same_bytes(name_in(&self.text, &self.names, k), key)
        };
        let k = if is(next) {
            next
        } else if is(next.wrapping_sub(1)) {
            next.wrapping_sub(1)
        } else {
            let Some(&k) = self.table.find(hash, |&k| {
                same_bytes(name_in(&self.text, &self.names, k), key)
            }) else {
                return &[];
            };
            k
        };
        self.next.set(k.wrapping_add(1));
        let k = k as usize;
        if self.one_each {
            return self.values.get(k..k + 1).unwrap_or_default();
        }
        let start = k
            .checked_sub(1)
            .and_then(|p| self.ends.get(p))
            .map_or(0, |&e| e as usize);
        let end = self.ends.get(k).map_or(start, |&e| e as usize);
        self.values.get(start..end).unwrap_or_default()
    }
}

/// The part of a folded `key` before the first `open` byte, if it has one. A name is a few
/// bytes: a plain search beats `memchr`'s call and set-up.
fn before(key: &str, open: u8) -> Option<&str> {
    let at = key.bytes().position(|b| b == open)?;
    key.get(..at)
}

/// [`before`] of bytes.
fn before_bytes(key: &[u8], open: u8) -> Option<&[u8]> {
    let at = key.iter().position(|&b| b == open)?;
    key.get(..at)
}

impl<T: Copy> NameIndex<T> {
    /// A builder for about `capacity` names, whose arrays open their index with `open` (an
    /// ASCII bracket).
    pub(crate) fn builder(open: char, capacity: usize) -> NameIndexBuilder<T> {
        NameIndexBuilder {
            open: open as u8,
            buf: Vec::new(),
            exact: Groups::with_capacity(capacity),
            elements: Groups::with_capacity(0),
            in_exact: Vec::with_capacity(capacity),
            in_arrays: Vec::new(),
        }
    }

    /// The declarations named exactly `key` (a [`fold`]ed name).
    pub(crate) fn exact(&self, key: &str) -> &[T] {
        self.exact.get(key.as_bytes())
    }

    /// Every element of the array `key` (a [`fold`]ed name without index).
    pub(crate) fn elements(&self, key: &str) -> &[T] {
        self.elements.get(key.as_bytes())
    }

    /// The declarations named exactly `key` (a [`fold`]ed name), else every element of the
    /// array it names or indexes: [`NameIndex::exact`], else [`NameIndex::elements`] of
    /// [`NameIndex::array_of`] `key` (or of `key`), a name without index hashed once for both.
    pub(crate) fn exact_else_elements(&self, key: &str) -> &[T] {
        self.exact_else_elements_folded(key.as_bytes())
    }

    /// [`NameIndex::exact_else_elements`] of a folded name's bytes.
    fn exact_else_elements_folded(&self, key: &[u8]) -> &[T] {
        self.exact_else_elements_hashed(key, hash_of(key))
    }

    /// [`NameIndex::exact_else_elements_folded`] of `key` hashed as `hash`.
    fn exact_else_elements_hashed(&self, key: &[u8], hash: u64) -> &[T] {
        let exact = self.exact.get_hashed(key, hash);
        if !exact.is_empty() || self.elements.names.is_empty() {
            return exact;
        }
        match before_bytes(key, self.open) {
            Some(array) => self.elements.get(array),
            None => self.elements.get_hashed(key, hash),
        }
    }

    /// [`NameIndex::exact_else_elements`] of the [`fold`] of source bytes `raw`, read as they
    /// are: `None` when they do not fold byte by byte (a blank, a byte beyond ASCII), and the
    /// caller folds them. A module's motions name 10,000 targets: folding each into a buffer
    /// cost more than finding it.
    pub(crate) fn exact_else_elements_raw(&self, raw: &[u8]) -> Option<&[T]> {
        if let Some(short) = ShortKey::of(raw, true) {
            let bytes = short.word.to_le_bytes();
            let key = bytes.get(..short.len)?;
            return Some(self.exact_else_elements_hashed(key, short.hash()));
        }
        let mut key = [0; RAW_KEY];
        let key = fold_ascii_into(&mut key, raw)?;
        Some(self.exact_else_elements_folded(key))
    }

    /// The array `key` indexes (`PARR` for `PARR{I}`), if it has an index.
    pub(crate) fn array_of<'k>(&self, key: &'k str) -> Option<&'k str> {
        before(key, self.open)
    }
}

impl<T: Copy> NameIndexBuilder<T> {
    /// Adds the declaration of `name` (as written) at `at`.
    pub(crate) fn insert(&mut self, name: &str, at: T) {
        self.insert_utf8(name.as_bytes(), at);
    }

    /// [`insert`](Self::insert) of a name's UTF-8 bytes (as a position list keeps them).
    pub(crate) fn insert_utf8(&mut self, name: &[u8], at: T) {
        let NameIndexBuilder {
            open,
            buf,
            exact,
            elements,
            in_exact,
            in_arrays,
        } = self;
        let short = ShortKey::of(name, false);
        let word = short.map_or([0; 8], |s| s.word.to_le_bytes());
        let (key, hash) = match short.and_then(|s| word.get(..s.len).zip(Some(s.hash()))) {
            Some(short) => short,
            None => {
                let key = fold_utf8_into(buf, name);
                (key, hash_of(key))
            }
        };
        if let Some(array) = before_bytes(key, *open) {
            in_arrays.push((elements.intern(array), at));
        }
        in_exact.push((exact.intern_hashed(key, hash), at));
    }

    /// The index of everything inserted.
    pub(crate) fn build(self) -> NameIndex<T> {
        let NameIndexBuilder {
            open,
            mut exact,
            mut elements,
            in_exact,
            in_arrays,
            ..
        } = self;
        exact.fill(in_exact);
        elements.fill(in_arrays);
        NameIndex {
            open,
            exact,
            elements,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    #[test]
    fn first_letters_let_through_every_reference_that_folds_to_a_name() {
        // Every Latin-1 character, and one beyond, as a name's first character (after blanks
        // or not), against every byte as a reference's (after blanks or not), and the empty
        // name: whenever the two fold alike, the reference is let through.
        let mut firsts: Vec<String> = (0u8..=255).map(|b| format!("{}10", b as char)).collect();
        firsts.push("\u{391}10".to_owned());
        for name in firsts {
            for name in [name.clone(), format!(" {name}")] {
                let mut letters = FirstLetters::new();
                letters.insert(&name);
                // The same name as its UTF-8 bytes.
                let mut from_bytes = FirstLetters::new();
                from_bytes.insert_utf8(name.as_bytes());
                let mut folded = String::new();
                let key = fold_str_into(&mut folded, &name).to_owned();
                for b in 0u8..=255 {
                    for raw in [vec![b, b'1', b'0'], vec![b'\t', b, b'1', b'0']] {
                        let mut buf = String::new();
                        if fold_into(&mut buf, &raw) == key {
                            assert!(letters.may_start(&raw), "{name:?} {raw:?}");
                        }
                        assert_eq!(
                            from_bytes.may_start(&raw),
                            letters.may_start(&raw),
                            "{name:?} {raw:?}"
                        );
                    }
                }
                assert!(!letters.may_start(b"") && !letters.may_start(b"  "));
            }
        }
        let mut empty = FirstLetters::new();
        empty.insert(" ");
        assert!(empty.may_start(b" ") && !empty.may_start(b"p"));
        let mut p = FirstLetters::new();
        p.insert("p10");
        assert!(p.may_start(b"P10") && p.may_start(b"p") && !p.may_start(b"v1000"));
    }

    #[test]
    fn words_and_prefixes_are_compared_as_the_folded_bytes_compare() {
        let folded = |b: &[u8]| -> Vec<u8> {
            b.iter()
                .filter(|c| !c.is_ascii_whitespace())
                .map(u8::to_ascii_uppercase)
                .collect()
        };
        let names: [&[u8]; 10] = [
            b"",
            b"tool0",
            b"TOOL0",
            b" tool0",
            b"t ool0",
            b"tGun",
            b"MoveL",
            b"\xc4tool",
            b"\tmove",
            b"m",
        ];
        let words: [&[u8]; 7] = [b"", b"tool0", b"move", b"m", b"t", b"\xe4tool", b" tool0"];
        for n in names {
            for w in words {
                let (key, word) = (folded(n), w.to_ascii_uppercase());
                assert_eq!(NameKey(n).is(w), key == word, "{n:?} is {w:?}");
                assert_eq!(
                    NameKey(n).starts_with(w),
                    key.starts_with(&word),
                    "{n:?} starts with {w:?}"
                );
            }
        }
    }

    #[test]
    fn keys_ignore_case_and_blanks_and_hash_alike() {
        let (a, b) = (NameKey(b"pArr{ 2 }"), NameKey(b"PARR{2}"));
        assert_eq!(a, b);
        let h = BuildHasherDefault::<NameHasher>::default();
        assert_eq!(h.hash_one(a), h.hash_one(b));
        // Short and long, with blanks or without: equal keys hash alike.
        for (x, y) in [
            (&b"tGun"[..], &b" TGUN\t"[..]),
            (b"pApproach_10", b"PAPPROACH_10"),
            (b"pApproach_10", b"p Approach_10"),
            (b"p10abcde", b"P10ABCD E"),
            (b"\xc4p", b"\xc4P"),
        ] {
            assert_eq!(NameKey(x), NameKey(y));
            assert_eq!(
                h.hash_one(NameKey(x)),
                h.hash_one(NameKey(y)),
                "{x:?} {y:?}"
            );
        }
        assert_ne!(a, NameKey(b"parr{3}"));
        assert!(NameKey(b"Tool0").is(b"tool0"));
        assert!(NameKey(b"SearchL").starts_with(b"search"));
        assert!(NameKey(b"z10").numbered(b'z') && !NameKey(b"z").numbered(b'z'));
        assert!(!NameKey(b"zone").numbered(b'z'));
        // A key's first letter, past blanks and in either case, is what FirstLetters keeps.
        let mut letters = FirstLetters::new();
        letters.insert_utf8(a.0);
        letters.insert_utf8(b" t");
        assert!(letters.may_start(b.0) && letters.may_start(b"T1") && !letters.may_start(b" "));
        let mut blank = FirstLetters::new();
        blank.insert_utf8(b" ");
        assert!(blank.may_start(b"") && !blank.may_start(b"t"));
        assert_eq!(fold("p[ 3 ]"), "P[3]");
        let mut buf = String::new();
        assert_eq!(fold_into(&mut buf, b"pArr{ 2 }"), "PARR{2}");
    }

    #[test]
    fn short_keys_fold_and_hash_as_the_bytes_folded_one_by_one() {
        // Every byte, in each place of names of one to nine bytes around it, both readings.
        let fill = [b'p', b'A', b'{', b'9', b'z', b'_', b'~', b'@'];
        for b in 0u8..=255 {
            for len in 0..=9usize {
                for at in 0..len.max(1) {
                    let mut name: Vec<u8> = fill.iter().cycle().take(len).copied().collect();
                    if let Some(c) = name.get_mut(at) {
                        *c = b;
                    }
                    for ascii in [true, false] {
                        let plain = name.iter().all(|&c| c > b' ' && (c.is_ascii() || !ascii));
                        let short = ShortKey::of(&name, ascii);
                        assert_eq!(short.is_some(), plain && (1..=8).contains(&len), "{name:?}");
                        let Some(short) = short else { continue };
                        let folded: Vec<u8> = name.iter().map(u8::to_ascii_uppercase).collect();
                        let mut buf = Vec::new();
                        assert_eq!(fold_utf8_into(&mut buf, &name), folded);
                        assert_eq!(&short.word.to_le_bytes()[..short.len], &folded[..]);
                        assert_eq!(short.hash(), hash_of(&folded), "{name:?}");
                        if ascii {
                            let mut key = [0; RAW_KEY];
                            assert_eq!(fold_ascii_into(&mut key, &name), Some(&folded[..]));
                            let mut text = String::new();
                            assert_eq!(fold_into(&mut text, &name).as_bytes(), folded);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn same_bytes_is_slice_equality() {
        let texts: Vec<Vec<u8>> = (0..=10usize)
            .flat_map(|len| {
                (0..len.max(1)).map(move |at| {
                    let mut t: Vec<u8> = (0..len as u8).map(|b| b'a' + b).collect();
                    if let Some(c) = t.get_mut(at) {
                        *c = 0;
                    }
                    t
                })
            })
            .collect();
        for a in &texts {
            for b in &texts {
                assert_eq!(same_bytes(a, b), a == b, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn writing_bytes_hashes_as_zero_padded_words_did() {
        // The plain form: each chunk of eight copied into a zeroed word.
        fn plain(bytes: &[u8]) -> u64 {
            let mut h = NameHasher::default();
            for chunk in bytes.chunks(8) {
                let mut word = [0u8; 8];
                word[..chunk.len()].copy_from_slice(chunk);
                h.0 = (h.0.rotate_left(5) ^ u64::from_le_bytes(word)).wrapping_mul(K);
            }
            h.finish()
        }
        let text: Vec<u8> = (0..40u8).map(|b| b.wrapping_mul(37) ^ 0xA5).collect();
        for start in 0..8 {
            for end in start..text.len() {
                let bytes = &text[start..end];
                assert_eq!(hash_of(bytes), plain(bytes), "{start}..{end}");
            }
        }
    }

    #[test]
    fn names_differing_in_their_last_bytes_spread_over_low_bits() {
        let h = BuildHasherDefault::<NameHasher>::default();
        let low: std::collections::BTreeSet<u64> = (0..64)
            .map(|i| h.hash_one(NameKey(format!("XP1000{i:02}").as_bytes())) & 63)
            .collect();
        assert!(low.len() > 32, "{}", low.len());
    }

    #[test]
    fn the_index_finds_names_elements_and_whole_arrays() {
        let mut b = NameIndex::builder('{', 4);
        b.insert("p10", 0);
        b.insert("pArr{1}", 1);
        b.insert("pArr{ 2 }", 2);
        b.insert("P10", 3);
        let ix = b.build();
        assert_eq!(ix.exact("P10"), [0, 3]);
        assert_eq!(ix.exact("PARR{2}"), [2]);
        assert_eq!(ix.elements("PARR"), [1, 2]);
        assert_eq!(ix.array_of("PARR{I}"), Some("PARR"));
        assert_eq!(ix.array_of("P10"), None);
        assert!(ix.exact("PARR").is_empty());
        assert!(ix.elements("P10").is_empty());
    }

    #[test]
    fn exact_else_elements_is_the_exact_name_else_its_array() {
        // One index with arrays, one without (whose empty element table is never hashed).
        let mut with = NameIndex::builder('{', 0);
        let mut without = NameIndex::builder('{', 0);
        for (i, n) in ["p10", "pArr{1}", "pArr{ 2 }", "P10", "q"]
            .iter()
            .enumerate()
        {
            with.insert(n, i);
            if !n.contains('{') {
                without.insert(n, i);
            }
        }
        for ix in [with.build(), without.build()] {
            for key in [
                "P10", "PARR{2}", "PARR{9}", "PARR{I}", "PARR", "Q", "R", "R{1}", "",
            ] {
                let general = match ix.exact(key) {
                    [] => ix.elements(ix.array_of(key).unwrap_or(key)),
                    hits => hits,
                };
                assert_eq!(ix.exact_else_elements(key), general, "{key}");
            }
            // Source bytes read as they are, or folded where they do not fold byte by byte.
            for raw in [
                &b"p10"[..],
                b"P10",
                b" p10",
                b"pArr{2}",
                b"parr{ 2 }",
                b"pArr{i}",
                b"pArr",
                b"q",
                b"r{1}",
                b"",
                b"pArr{123456789012345678901234567890}",
                b"p\xe410",
            ] {
                let mut buf = String::new();
                let folded = ix.exact_else_elements(fold_into(&mut buf, raw));
                let read = ix.exact_else_elements_raw(raw);
                assert!(read.is_none_or(|r| r == folded), "{raw:?}");
                let plain = raw
                    .iter()
                    .all(|&b| b.is_ascii() && !b.is_ascii_whitespace());
                assert_eq!(read.is_some(), plain && raw.len() <= RAW_KEY, "{raw:?}");
            }
        }
        let mut b = NameIndex::builder('{', 0);
        b.insert("pArr{1}", 1);
        b.insert("pArr{2}", 2);
        let ix = b.build();
        assert_eq!(ix.exact_else_elements("PARR"), [1, 2]);
        assert_eq!(ix.exact_else_elements("PARR{I}"), [1, 2]);
        assert_eq!(ix.exact_else_elements("PARR{2}"), [2]);
    }

    #[test]
    fn the_index_keeps_every_name_through_growth_in_insertion_order() {
        let mut b = NameIndex::builder('[', 0);
        for i in 0..1000u32 {
            b.insert(&format!("p{}", i % 300), i);
            b.insert(&format!("a[{}]", i % 7), i);
        }
        let ix = b.build();
        assert_eq!(ix.exact("P7"), [7, 307, 607, 907]);
        assert_eq!(ix.exact("A[3]").len(), 143);
        assert_eq!(ix.elements("A").len(), 1000);
        assert!(ix.elements("A").windows(2).all(|w| w[0] < w[1]));
        assert!(ix.exact("P300").is_empty());
    }

    proptest::proptest! {
        /// Whatever the order of the lookups (the declaration order the guesses follow, the
        /// same name again, names declared twice, names not declared), each finds what a map
        /// built here from the insertions says.
        #[test]
        fn lookups_in_any_order_find_what_a_map_of_the_insertions_says(
            names in proptest::collection::vec(0u32..60, 0..80),
            lookups in proptest::collection::vec(
                proptest::prop_oneof![0u32..70, proptest::strategy::Just(u32::MAX)], 0..120),
            in_order in proptest::bool::ANY,
        ) {
            let name = |n: u32| if n == u32::MAX { String::new() } else { format!("P{n}") };
            let mut b = NameIndex::builder('{', names.len());
            let mut expected: HashMap<String, Vec<u32>> = HashMap::new();
            for (at, &n) in names.iter().enumerate() {
                b.insert(&name(n), at as u32);
                expected.entry(name(n)).or_default().push(at as u32);
            }
            let ix = b.build();
            // Declaration order with repeats, as a program's motions name them, or any order.
            let asked: Vec<u32> = if in_order {
                names.iter().flat_map(|&n| [n, n]).chain(lookups).collect()
            } else {
                lookups
            };
            for n in asked {
                let want = expected.get(&name(n)).map_or(&[][..], Vec::as_slice);
                proptest::prop_assert_eq!(ix.exact(&name(n)), want, "{}", name(n));
            }
        }
    }
}
