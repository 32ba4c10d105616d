//! Cache of the slow intermediate results of `lamdyn run`, keyed by their inputs: the projected
//! modal model (the eigen solution on the channels, with its residual terms) and the modal
//! identification. A key is the FNV-1a 64-bit hash of everything the result depends on (the
//! model spec and mesh file bytes, the channels, the options; the FRF values for the
//! identification; and the code: the package version and `LAMDYN_SOURCE_HASH`, the hash of the
//! sources of the crates that compute them, set by build.rs), so changing only the law, the
//! stack or the uncertainty options re-uses both, and changing any input, or the code, misses.
//! Files are written to a temporary name and renamed: a crash leaves no half-written entry.
//!
//! Every entry is checked before it is used: a header holds a magic word, the entry's key, the
//! payload's length and its FNV-1a checksum (any change confined to one byte changes the
//! checksum: each step of FNV-1a is a bijection of its state). An entry that fails (a bit
//! flipped on disk, a truncated copy, a file renamed to another key) is removed, noted in
//! [`Cache::notes`] for the report, and its stage recomputes.

use crate::error::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// First bytes of a cache entry (version 2: with the header; version-1 entries are refused
/// and recomputed).
const MAGIC: &[u8; 8] = b"LAMDYNC2";

/// Header length: magic, key, payload length, checksum.
const HEADER: usize = 32;

/// FNV-1a 64 of `data` (no length prefix): the payload's checksum.
fn checksum(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// FNV-1a, 64 bits (Fowler–Noll–Vo): a stable hash across runs, platforms and Rust versions.
#[derive(Debug, Clone, Copy)]
pub struct Key(u64);

impl Key {
    /// The empty key.
    pub fn new(kind: &str) -> Self {
        Self(0xcbf2_9ce4_8422_2325).bytes(kind.as_bytes())
    }

    /// The key extended by `data` (its length first, so concatenations cannot collide).
    pub fn bytes(mut self, data: &[u8]) -> Self {
        for b in (data.len() as u64).to_le_bytes().iter().chain(data) {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    /// The key extended by a number's bits.
    pub fn f64(self, v: f64) -> Self {
        self.bytes(&v.to_le_bytes())
    }

    /// Hex form for file names.
    pub fn hex(self) -> String {
        format!("{:016x}", self.0)
    }
}

/// A cache folder (absent: caching off).
#[derive(Debug, Default)]
pub struct Cache {
    dir: Option<PathBuf>,
    notes: Mutex<Vec<String>>,
}

impl Cache {
    /// A cache in `dir`, or none.
    pub fn new(dir: Option<PathBuf>) -> Self {
        Self {
            dir,
            notes: Mutex::new(Vec::new()),
        }
    }

    /// What happened to entries that failed their check (for the report's warnings).
    pub fn notes(&self) -> Vec<String> {
        self.notes.lock().map(|n| n.clone()).unwrap_or_default()
    }

    fn path(&self, name: &str, key: Key) -> Option<PathBuf> {
        self.dir
            .as_ref()
            .map(|d| d.join(format!("{name}-{}", key.hex())))
    }

    /// The bytes stored under `name` and `key`, if there is an entry and it passes its check
    /// (module docs); a failing entry is removed and noted.
    pub fn get(&self, name: &str, key: Key) -> Option<Vec<u8>> {
        let path = self.path(name, key)?;
        let bytes = match read_entry(&path) {
            Ok(Some(bytes)) => bytes,
            Ok(None) => return None,
            Err(why) => {
                self.refuse(&path, why);
                return None;
            }
        };
        match unwrap_entry(&bytes, key) {
            Ok(payload) => Some(payload.to_vec()),
            Err(why) => {
                self.refuse(&path, why);
                None
            }
        }
    }

    /// Removes the entry at `path` (a link itself, not its target) and notes why.
    fn refuse(&self, path: &Path, why: &str) {
        let _ = std::fs::remove_file(path);
        if let Ok(mut n) = self.notes.lock() {
            n.push(format!(
                "cache entry '{}' failed its check ({why}): removed and recomputed",
                path.display()
            ));
        }
    }

    /// Stores `bytes` under `name` and `key` with the checked header (temporary file, then
    /// rename).
    pub fn put(&self, name: &str, key: Key, bytes: &[u8]) -> Result<()> {
        let Some(path) = self.path(name, key) else {
            return Ok(());
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the cache folder '{}'", dir.display()))?;
        // Unique per process and call: jobs of a batch share one cache folder from several
        // processes and threads, and may store the same key at once (the last rename wins;
        // both entries are the same bytes).
        static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let serial = SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = path.with_extension(format!("tmp-{}-{serial}", std::process::id()));
        let mut entry = Vec::with_capacity(HEADER + bytes.len());
        entry.extend_from_slice(MAGIC);
        entry.extend_from_slice(&key.0.to_le_bytes());
        entry.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        entry.extend_from_slice(&checksum(bytes).to_le_bytes());
        entry.extend_from_slice(bytes);
        std::fs::write(&tmp, entry).with_context(|| format!("cannot write '{}'", tmp.display()))?;
        std::fs::rename(&tmp, &path)
            .with_context(|| format!("cannot write '{}'", path.display()))?;
        Ok(())
    }

    /// Whether caching is on.
    pub fn enabled(&self) -> bool {
        self.dir.is_some()
    }
}

/// The bytes of the entry at `path`: `None` when there is none, an error when it is not a
/// regular file (a link, a pipe, a device: reading one could block or never end) or holds
/// other than its header announces. At most its header and the payload it announces are read.
fn read_entry(path: &Path) -> std::result::Result<Option<Vec<u8>>, &'static str> {
    use std::io::Read;
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(None);
    };
    if !meta.file_type().is_file() {
        return Err("not a regular file");
    }
    let mut file = std::fs::File::open(path).map_err(|_| "cannot be opened")?;
    let mut bytes = vec![0u8; HEADER.min(meta.len() as usize)];
    file.read_exact(&mut bytes).map_err(|_| "cannot be read")?;
    if bytes.len() < HEADER {
        return Ok(Some(bytes));
    }
    let mut word = [0u8; 8];
    word.copy_from_slice(&bytes[16..24]);
    let announced = u64::from_le_bytes(word);
    if meta.len().checked_sub(HEADER as u64) != Some(announced) {
        return Err("its length does not match its header");
    }
    file.take(announced)
        .read_to_end(&mut bytes)
        .map_err(|_| "cannot be read")?;
    Ok(Some(bytes))
}

/// The payload of an entry whose header matches `key` and whose checksum holds.
fn unwrap_entry(bytes: &[u8], key: Key) -> Result<&[u8], &'static str> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return Err("not a lamdyn cache entry of this version");
    }
    let word = |k: usize| {
        let mut w = [0u8; 8];
        w.copy_from_slice(&bytes[8 * k..8 * k + 8]);
        u64::from_le_bytes(w)
    };
    let payload = &bytes[HEADER..];
    if word(1) != key.0 {
        return Err("its key is another entry's");
    }
    if word(2) != payload.len() as u64 {
        return Err("its length does not match its header");
    }
    if word(3) != checksum(payload) {
        return Err("checksum mismatch");
    }
    Ok(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_is_stable_and_separates_concatenations() {
        // FNV-1a 64 of "a" is 0xaf63dc4c8601ec8c; our key prefixes lengths, so check the core
        // on the offset basis directly.
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for b in b"a" {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
        let ab = Key::new("k").bytes(b"ab").bytes(b"c").hex();
        let a_bc = Key::new("k").bytes(b"a").bytes(b"bc").hex();
        assert_ne!(ab, a_bc);
        assert_eq!(ab, Key::new("k").bytes(b"ab").bytes(b"c").hex());
    }

    #[test]
    fn put_then_get_and_off_when_no_folder() {
        let dir = lamdyn_testkit::TempDir::new("cache");
        let c = Cache::new(Some(dir.to_path_buf()));
        let k = Key::new("x").f64(1.5);
        assert!(c.get("m", k).is_none());
        c.put("m", k, b"hello").unwrap();
        assert_eq!(c.get("m", k).unwrap(), b"hello");
        let off = Cache::new(None);
        off.put("m", k, b"x").unwrap();
        assert!(off.get("m", k).is_none());
        assert!(c.notes().is_empty());
    }

    /// Every single-bit flip anywhere in an entry (header or payload), a truncation and an
    /// entry copied under another key are caught: the entry is removed, noted, not returned.
    #[test]
    fn damaged_entries_are_refused_and_removed() {
        let dir = lamdyn_testkit::TempDir::new("cache-damage");
        let c = Cache::new(Some(dir.to_path_buf()));
        let k = Key::new("x").f64(2.5);
        let payload: Vec<u8> = (0..200u8).collect();
        c.put("m", k, &payload).unwrap();
        let path = c.path("m", k).unwrap();
        let good = std::fs::read(&path).unwrap();
        for byte in 0..good.len() {
            for bit in 0..8 {
                let mut bad = good.clone();
                bad[byte] ^= 1 << bit;
                std::fs::write(&path, &bad).unwrap();
                assert!(c.get("m", k).is_none(), "flip of bit {bit} in byte {byte}");
                assert!(!path.exists(), "damaged entry left in place");
            }
        }
        std::fs::write(&path, &good[..good.len() - 1]).unwrap();
        assert!(c.get("m", k).is_none());
        let other = Key::new("x").f64(3.5);
        std::fs::write(c.path("m", other).unwrap(), &good).unwrap();
        assert!(c.get("m", other).is_none());
        assert_eq!(c.notes().len(), good.len() * 8 + 2);
        std::fs::write(&path, &good).unwrap();
        assert_eq!(c.get("m", k).unwrap(), payload);
    }

    /// An entry that is not a regular file is refused and its link removed before it is read:
    /// a link to an endless device, a link to another file, a named pipe (which would block a
    /// read forever).
    #[test]
    fn entries_that_are_not_regular_files_are_refused_unread() {
        let dir = lamdyn_testkit::TempDir::new("cache-special");
        let c = Cache::new(Some(dir.to_path_buf()));
        let k = Key::new("x").f64(4.5);
        c.put("m", k, b"payload").unwrap();
        let path = c.path("m", k).unwrap();
        let target = dir.to_path_buf().join("elsewhere");
        std::fs::rename(&path, &target).unwrap();
        for link_to in [Path::new("/dev/zero"), target.as_path()] {
            std::os::unix::fs::symlink(link_to, &path).unwrap();
            assert!(c.get("m", k).is_none(), "{}", link_to.display());
            assert!(std::fs::symlink_metadata(&path).is_err(), "the link stays");
        }
        assert_eq!(
            std::fs::read(&target).unwrap().len(),
            HEADER + 7,
            "the target is kept"
        );
        let fifo = std::process::Command::new("mkfifo").arg(&path).status();
        if fifo.is_ok_and(|s| s.success()) {
            assert!(c.get("m", k).is_none());
            assert!(std::fs::symlink_metadata(&path).is_err());
        }
        assert!(c.notes().iter().all(|n| n.contains("not a regular file")));
    }

    /// A result stored as JSON (the EMA's) comes back with the same bits: serde_json's
    /// default float parser is not correctly rounded (0.9641358461522235, an EMA mode's MPC,
    /// came back one unit in the last place up, and a re-run from the cache differed from the
    /// first run in the last digits of every layered G*), so the workspace enables its
    /// `float_roundtrip`. Checked on the value above and 100 000 pseudo-random finite doubles
    /// over the whole exponent range.
    #[test]
    fn json_floats_come_back_with_the_same_bits() {
        let back =
            |x: f64| serde_json::from_slice::<f64>(&serde_json::to_vec(&x).unwrap()).unwrap();
        assert_eq!(
            back(0.964_135_846_152_223_5).to_bits(),
            0.964_135_846_152_223_5f64.to_bits()
        );
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut checked = 0;
        while checked < 100_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let x = f64::from_bits(state);
            if !x.is_finite() {
                continue;
            }
            assert_eq!(back(x).to_bits(), x.to_bits(), "{x:e}");
            checked += 1;
        }
    }
}
