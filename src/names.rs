//! Names as robot languages compare them, for every dialect: ASCII case-insensitive, blanks
//! ignored (`pArr{ 2 }` is `PARR{2}`, `p[ 3 ]` is `P[3]`), and one fast hasher for the maps
//! keyed by them.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

const K: u64 = 0x51_7c_c1_b7_27_22_0a_95;

/// Names are short, trusted-enough keys (the file is the user's own program) and a module holds
/// hundreds of thousands of them: SipHash showed up as a tenth of the run time. This is the
/// multiply-rotate hash of rustc's `FxHasher` with a finaliser, written out to avoid a
/// dependency.
#[derive(Default, Clone, Copy)]
pub(crate) struct NameHasher(u64);

impl Hasher for NameHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.0 = (self.0.rotate_left(5) ^ u64::from_le_bytes(word)).wrapping_mul(K);
        }
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

    /// The name is `word` (any case).
    pub(crate) fn is(&self, word: &[u8]) -> bool {
        self.bytes().eq(word.iter().map(u8::to_ascii_uppercase))
    }

    /// The name starts with `prefix` (any case).
    pub(crate) fn starts_with(&self, prefix: &[u8]) -> bool {
        let mut b = self.bytes();
        prefix
            .iter()
            .all(|&l| b.next() == Some(l.to_ascii_uppercase()))
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
    fn hash<H: Hasher>(&self, state: &mut H) {
        for b in self.bytes() {
            state.write_u8(b);
        }
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
    name.chars()
        .filter(|c| !c.is_ascii_whitespace())
        .map(|c| c.to_ascii_uppercase())
        .collect()
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

/// Declared names of a program, folded, with the elements of each array under the array's name:
/// what both languages' usage resolvers look a motion's references up in. `T` says where the
/// declaration is (an index into a file's positions, …).
pub(crate) struct NameIndex<T> {
    /// The bracket that opens an array index (`{` in RAPID, `[` in KRL).
    open: char,
    exact: NameMap<String, Vec<T>>,
    elements: NameMap<String, Vec<T>>,
}

impl<T: Copy> NameIndex<T> {
    pub(crate) fn new(open: char, capacity: usize) -> NameIndex<T> {
        NameIndex {
            open,
            exact: NameMap::with_capacity_and_hasher(capacity, Default::default()),
            elements: NameMap::default(),
        }
    }

    /// Adds the declaration of `name` (as written) at `at`.
    pub(crate) fn insert(&mut self, name: &str, at: T) {
        let key = fold(name);
        if let Some((array, _)) = key.split_once(self.open) {
            match self.elements.get_mut(array) {
                Some(v) => v.push(at),
                None => {
                    self.elements.insert(array.to_owned(), vec![at]);
                }
            }
        }
        self.exact.entry(key).or_default().push(at);
    }

    /// The declarations named exactly `key` (a [`fold`]ed name).
    pub(crate) fn exact(&self, key: &str) -> &[T] {
        self.exact.get(key).map_or(&[], Vec::as_slice)
    }

    /// Every element of the array `key` (a [`fold`]ed name without index).
    pub(crate) fn elements(&self, key: &str) -> &[T] {
        self.elements.get(key).map_or(&[], Vec::as_slice)
    }

    /// The array `key` indexes (`PARR` for `PARR{I}`), if it has an index.
    pub(crate) fn array_of<'k>(&self, key: &'k str) -> Option<&'k str> {
        key.split_once(self.open).map(|(array, _)| array)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    #[test]
    fn keys_ignore_case_and_blanks_and_hash_alike() {
        let (a, b) = (NameKey(b"pArr{ 2 }"), NameKey(b"PARR{2}"));
        assert_eq!(a, b);
        let h = BuildHasherDefault::<NameHasher>::default();
        assert_eq!(h.hash_one(a), h.hash_one(b));
        assert_ne!(a, NameKey(b"parr{3}"));
        assert!(NameKey(b"Tool0").is(b"tool0"));
        assert!(NameKey(b"SearchL").starts_with(b"search"));
        assert!(NameKey(b"z10").numbered(b'z') && !NameKey(b"z").numbered(b'z'));
        assert!(!NameKey(b"zone").numbered(b'z'));
        assert_eq!(fold("p[ 3 ]"), "P[3]");
        let mut buf = String::new();
        assert_eq!(fold_into(&mut buf, b"pArr{ 2 }"), "PARR{2}");
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
        let mut ix = NameIndex::new('{', 4);
        ix.insert("p10", 0);
        ix.insert("pArr{1}", 1);
        ix.insert("pArr{ 2 }", 2);
        assert_eq!(ix.exact("P10"), [0]);
        assert_eq!(ix.exact("PARR{2}"), [2]);
        assert_eq!(ix.elements("PARR"), [1, 2]);
        assert_eq!(ix.array_of("PARR{I}"), Some("PARR"));
        assert_eq!(ix.array_of("P10"), None);
        assert!(ix.exact("PARR").is_empty());
    }
}
