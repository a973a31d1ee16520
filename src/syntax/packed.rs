//! An append-only log of small variable-length records, kept in chunks.
//!
//! A transform of a large program records one edit per written number and one change per
//! target, hundreds of thousands of each, and holds them next to the source and the output
//! being built: as fixed-size structs in vectors grown by doubling they were a third of
//! `correct`'s heap once the model was gone (a 20 MB module: 22 MB of edits, 10 MB of change
//! records). Packed as bytes (offsets as deltas in LEB128, texts inline) a record takes about
//! what it says, and chunks that are never reallocated hold at most one chunk's room to spare:
//! no block twice the size it needs, no copy of the whole log when it grows.

/// The first chunk's room: a small file's log stays small (a batch of many small programs
/// keeps every program's change records).
const FIRST_CHUNK: usize = 256;

/// Chunks double up to this room. Above glibc's mmap threshold as the binary sets it (128 KiB),
/// so a chunk freed goes back to the system at once; the room to spare is at most this.
const MAX_CHUNK: usize = 256 * 1024;

/// The bytes of the records, in the order they were added; a record never spans two chunks.
#[derive(Clone, Default, PartialEq, Eq)]
pub(crate) struct Chunks {
    chunks: Vec<Vec<u8>>,
}

impl Chunks {
    /// The chunk to append a record of at most `max` bytes to: the last one, or a new one when
    /// the last has less room. Appending up to `max` bytes to it never reallocates.
    #[inline]
    pub(crate) fn room(&mut self, max: usize) -> &mut Vec<u8> {
        let fits = self
            .chunks
            .last()
            .is_some_and(|c| c.capacity() - c.len() >= max);
        if !fits {
            self.grow(max);
        }
        let last = self.chunks.len() - 1;
        &mut self.chunks[last]
    }

    #[cold]
    fn grow(&mut self, max: usize) {
        let next = self
            .chunks
            .last()
            .map_or(FIRST_CHUNK, |c| (c.capacity() * 2).min(MAX_CHUNK));
        self.chunks.push(Vec::with_capacity(next.max(max)));
    }

    /// Gives back the last chunk's room to spare (nothing more is to be added, or little).
    pub(crate) fn shrink_to_fit(&mut self) {
        if let Some(c) = self.chunks.last_mut() {
            c.shrink_to_fit();
        }
    }

    /// How many chunks.
    #[cfg(test)]
    pub(crate) fn chunks_len(&self) -> usize {
        self.chunks.len()
    }

    /// The bytes the records take (not the room to spare).
    #[cfg(test)]
    pub(crate) fn bytes(&self) -> usize {
        self.chunks.iter().map(Vec::len).sum()
    }

    /// Where the first record starts.
    pub(crate) fn start(&self) -> Place {
        Place { chunk: 0, at: 0 }
    }

    /// Where the next record added will start.
    pub(crate) fn end(&self) -> Place {
        match self.chunks.last() {
            Some(c) => Place {
                chunk: self.chunks.len() - 1,
                at: c.len(),
            },
            None => self.start(),
        }
    }

    /// The bytes from `place` to the end of its chunk, moving `place` to the next chunk when
    /// its own is read to the end (a record never spans two).
    #[inline]
    pub(crate) fn rest(&self, place: &mut Place) -> &[u8] {
        if let Some(c) = self.chunks.get(place.chunk)
            && place.at < c.len()
        {
            return &c[place.at..];
        }
        self.next_chunk(place)
    }

    #[cold]
    fn next_chunk(&self, place: &mut Place) -> &[u8] {
        while let Some(c) = self.chunks.get(place.chunk) {
            if place.at < c.len() {
                return &c[place.at..];
            }
            place.chunk += 1;
            place.at = 0;
        }
        &[]
    }
}

impl Chunks {
    /// The `len` bytes at `place` (within its chunk); empty if they are not there (a chunk
    /// released).
    pub(crate) fn get(&self, place: Place, len: usize) -> &[u8] {
        self.chunks
            .get(place.chunk)
            .and_then(|c| c.get(place.at..place.at.checked_add(len)?))
            .unwrap_or_default()
    }

    /// Frees the chunks before chunk `chunk` (a reader done with them): their places read as
    /// empty from now on, the others stay where they are.
    pub(crate) fn release_before(&mut self, chunk: usize) {
        for c in self.chunks.iter_mut().take(chunk) {
            if c.capacity() > 0 {
                *c = Vec::new();
            }
        }
    }
}

/// A place in [`Chunks`]: a chunk and a byte in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Place {
    /// The chunk.
    pub(crate) chunk: usize,
    /// The byte in the chunk.
    pub(crate) at: usize,
}

/// The most bytes [`put_varint`] writes.
pub(crate) const VARINT_MAX: usize = 10;

/// Writes `v` in LEB128 (seven bits a byte, low first, the high bit set on all but the last)
/// at `buf[*n..]`, moving `*n` past it; `buf` has room for [`VARINT_MAX`] bytes there.
#[inline]
pub(crate) fn put_varint(buf: &mut [u8], n: &mut usize, mut v: u64) {
    while v >= 0x80 {
        buf[*n] = (v as u8) | 0x80;
        *n += 1;
        v >>= 7;
    }
    buf[*n] = v as u8;
    *n += 1;
}

/// Appends `v` to `out` as [`put_varint`] writes it (a test holds the two equal): pushed
/// byte by byte, as a list of positions writes two dozen of them per target.
#[inline]
pub(crate) fn push_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Reads a [`put_varint`] number at `*at`, moving `*at` past it; `None` past the end.
#[inline]
pub(crate) fn read_varint(bytes: &[u8], at: &mut usize) -> Option<u64> {
    // Most numbers of a log (offsets between edits, lengths) take one byte.
    let b = *bytes.get(*at)?;
    if b < 0x80 {
        *at += 1;
        return Some(u64::from(b));
    }
    read_varint_long(bytes, at)
}

fn read_varint_long(bytes: &[u8], at: &mut usize) -> Option<u64> {
    read_varint_inlined(bytes, at)
}

/// [`read_varint`] written out where it is called, for a reader that takes several numbers in
/// a row (a position's head, read by every use of a position), where a call each was half of
/// the reading.
#[inline(always)]
pub(crate) fn read_varint_inlined(bytes: &[u8], at: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    let mut shift = 0;
    loop {
        let b = *bytes.get(*at)?;
        *at += 1;
        v |= u64::from(b & 0x7f).checked_shl(shift)?;
        if b < 0x80 {
            return Some(v);
        }
        shift += 7;
    }
}

/// A signed number as an unsigned one for [`put_varint`], small either side of zero.
#[inline]
pub(crate) fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// The inverse of [`zigzag`].
#[inline]
pub(crate) fn unzigzag(v: u64) -> i64 {
    ((v >> 1) as i64) ^ -((v & 1) as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_read_back_at_every_width() {
        let values = [
            0,
            1,
            127,
            128,
            300,
            16_383,
            16_384,
            u32::MAX as u64,
            u64::MAX,
        ];
        let mut out = vec![0; values.len() * VARINT_MAX];
        let mut n = 0;
        for v in values {
            put_varint(&mut out, &mut n, v);
        }
        out.truncate(n);
        assert_eq!(out[..4], [0, 1, 127, 0x80]);
        // Appended to a vector, the same bytes.
        let mut pushed = Vec::new();
        for v in values {
            push_varint(&mut pushed, v);
        }
        assert_eq!(pushed, out);
        let mut at = 0;
        for v in values {
            assert_eq!(read_varint(&out, &mut at), Some(v));
        }
        assert_eq!(at, out.len());
        assert_eq!(read_varint(&out, &mut at), None);
        // A number cut short is no number.
        assert_eq!(read_varint(&[0x80, 0x80], &mut 0), None);
        for v in [0, 1, -1, 63, -64, i64::MAX, i64::MIN] {
            assert_eq!(unzigzag(zigzag(v)), v);
        }
        assert_eq!(zigzag(-1), 1);
        assert_eq!(zigzag(1), 2);
    }

    #[test]
    fn records_stay_in_one_chunk_and_read_back_in_order() {
        let mut log = Chunks::default();
        let mut sizes = Vec::new();
        // 600 records of 1 to 40 bytes, and one larger than any chunk.
        for i in 0..600usize {
            let n = if i == 300 { MAX_CHUNK + 5 } else { 1 + i % 40 };
            sizes.push(n);
            let c = log.room(n);
            let cap = c.capacity();
            c.extend(std::iter::repeat_n(i as u8, n));
            assert_eq!(c.capacity(), cap, "record {i} reallocated its chunk");
        }
        assert!(log.chunks.len() > 3);
        assert!(log.chunks.iter().all(|c| c.capacity() <= MAX_CHUNK + 5));
        let mut place = log.start();
        for (i, n) in sizes.into_iter().enumerate() {
            let rest = log.rest(&mut place);
            assert!(rest.len() >= n);
            assert!(rest[..n].iter().all(|&b| b == i as u8), "record {i}");
            place.at += n;
        }
        assert!(log.rest(&mut place).is_empty());
        // The end of a full chunk reads as the start of the next one.
        let end = log.end();
        log.room(MAX_CHUNK).push(7);
        let mut at_end = end;
        assert_eq!(log.rest(&mut at_end), [7]);
        log.shrink_to_fit();
        let last = log.chunks.last().unwrap();
        assert_eq!(last.capacity(), last.len());
    }
}
