//! The on-disk cache of consistent bond weights: one file per correction problem, named by its
//! content key ([`peritherm_core::weights::store::key`]), so that a rerun or a sweep variant
//! that changes nothing the weights depend on loads them instead of solving again.
//!
//! A file is a fixed header (magic, key, counts, the BLAKE3 hash of the payload) and a payload
//! (the summary as JSON, the pair conductances as little-endian f64, the met flags as bytes).
//! Reading checks the length, the magic, the key, the counts and the hash while streaming: a
//! truncated or corrupt file is deleted and the weights are computed again, never trusted.
//! Files are written beside their place and renamed into it, so a reader sees a whole file or
//! none; the cache is kept under its size by deleting the least recently used files.

use peritherm_core::math::Real;
use peritherm_core::weights::store::{Key, Solved, SolvedRef, Store};
use peritherm_core::weights::Consistency;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// First bytes of every cache file (the format's version is its last digit).
const MAGIC: &[u8; 8] = b"PTWEIGH1";
/// Header bytes: magic, key, entries, nodes, summary length, payload hash.
const HEADER: usize = 8 + 32 + 8 + 8 + 8 + 32;
/// Extension of cache files.
const EXT: &str = "weights";
/// Default size of the cache, bytes (4 GiB).
pub const DEFAULT_BYTES: u64 = 4 << 30;
/// Environment variable naming the cache directory (`off` disables the cache).
pub const DIR_VAR: &str = "PERITHERM_CACHE";
/// Environment variable setting the cache's size (e.g. `2G`).
pub const SIZE_VAR: &str = "PERITHERM_CACHE_SIZE";
/// Bytes read or written per chunk: reading and writing stay in bounded memory.
const CHUNK: usize = 1 << 16;
/// Partial files older than this are left-overs of an interrupted write and are removed.
const STALE_PARTIAL: Duration = Duration::from_secs(3600);

/// A directory of cached weights of at most `max_bytes`.
#[derive(Debug, Clone)]
pub struct WeightsCache {
    /// The directory of the cache files.
    pub dir: PathBuf,
    /// Largest total size of the cache files, bytes.
    pub max_bytes: u64,
    /// Whether this process only reads (the ranks after the first of a distributed run).
    pub read_only: bool,
}

impl WeightsCache {
    /// A cache in `dir` of at most `max_bytes`.
    pub fn new(dir: impl Into<PathBuf>, max_bytes: u64) -> WeightsCache {
        WeightsCache {
            dir: dir.into(),
            max_bytes,
            read_only: false,
        }
    }

    /// The cache the options and the environment ask for: `dir` (or `$PERITHERM_CACHE`, or
    /// `$XDG_CACHE_HOME/peritherm/weights`, or `~/.cache/peritherm/weights`) of `bytes` (or
    /// `$PERITHERM_CACHE_SIZE`, or 4 GiB); None when the directory is `off` or there is no home.
    pub fn configured(
        dir: Option<&Path>,
        bytes: Option<f64>,
    ) -> Result<Option<WeightsCache>, String> {
        let dir = match dir {
            Some(d) => Some(d.to_path_buf()),
            None => std::env::var_os(DIR_VAR).map(PathBuf::from),
        };
        let dir = match dir {
            Some(d) if d.as_os_str() == "off" => return Ok(None),
            Some(d) => d,
            None => match default_dir() {
                Some(d) => d,
                None => return Ok(None),
            },
        };
        let bytes = match bytes {
            Some(b) => b,
            None => match std::env::var(SIZE_VAR) {
                Ok(s) => peritherm_core::budget::parse_bytes(&s)
                    .map_err(|e| format!("{SIZE_VAR}: {e}"))?,
                Err(_) => DEFAULT_BYTES as f64,
            },
        };
        Ok(Some(WeightsCache::new(dir, bytes as u64)))
    }

    /// The same cache, only read from.
    pub fn reading(&self) -> WeightsCache {
        WeightsCache {
            read_only: true,
            ..self.clone()
        }
    }

    /// The file of `key`.
    pub fn path(&self, key: &Key) -> PathBuf {
        self.dir.join(format!("{}.{EXT}", key.hex()))
    }

    /// Reads and checks the file of `key`; None if absent, or (deleting it) if it is not
    /// an intact file of that key with `entries` values and `nodes` flags.
    fn read(&self, key: &Key, entries: usize, nodes: usize) -> Option<Solved> {
        let path = self.path(key);
        let file = File::open(&path).ok()?;
        match read_checked(file, key, entries, nodes) {
            Some(solved) => {
                // least recently used: a load counts as a use
                if let Ok(f) = File::options().append(true).open(&path) {
                    let _ = f.set_modified(SystemTime::now());
                }
                Some(solved)
            }
            None => {
                let _ = std::fs::remove_file(&path);
                None
            }
        }
    }

    /// Writes `solved` (its summary serialised as `summary`) under `key` through a partial file
    /// and a rename.
    fn write(&self, key: &Key, summary: &[u8], solved: SolvedRef) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.dir)?;
        let path = self.path(key);
        let tmp = self
            .dir
            .join(format!(".{}.{}.partial", key.hex(), std::process::id()));
        let written = write_file(&tmp, key, summary, solved);
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
            return written;
        }
        // an interrupt waits for the rename (crate::staging::interrupt)
        let _guard = crate::atomic::writing();
        std::fs::rename(&tmp, &path)
    }

    /// Deletes the least recently used files until the cache holds at most `max_bytes`,
    /// and partial files left by interrupted writes.
    fn evict(&self) {
        let Ok(dir) = std::fs::read_dir(&self.dir) else {
            return;
        };
        let now = SystemTime::now();
        let mut files: Vec<(SystemTime, u64, PathBuf)> = Vec::new();
        for entry in dir.flatten() {
            let path = entry.path();
            let Ok(meta) = entry.metadata() else { continue };
            let modified = meta.modified().unwrap_or(now);
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.ends_with(".partial") {
                if now.duration_since(modified).unwrap_or_default() > STALE_PARTIAL {
                    let _ = std::fs::remove_file(&path);
                }
            } else if path.extension().is_some_and(|e| e == EXT) {
                files.push((modified, meta.len(), path));
            }
        }
        files.sort();
        let mut total: u64 = files.iter().map(|f| f.1).sum();
        for (_, len, path) in files {
            if total <= self.max_bytes {
                break;
            }
            if std::fs::remove_file(&path).is_ok() {
                total -= len;
            }
        }
    }
}

impl Store for WeightsCache {
    fn load(&self, key: &Key, entries: usize, nodes: usize) -> Option<Solved> {
        self.read(key, entries, nodes)
    }

    fn save(&self, key: &Key, solved: SolvedRef) {
        let Ok(summary) = serde_json::to_vec(solved.summary) else {
            return;
        };
        if self.read_only || file_bytes(&summary, solved) > self.max_bytes {
            return;
        }
        if self.write(key, &summary, solved).is_ok() {
            self.evict();
        }
    }
}

/// `$XDG_CACHE_HOME/peritherm/weights`, else `$HOME/.cache/peritherm/weights`.
fn default_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("peritherm").join("weights"))
}

/// The size of the file of `solved` with its summary serialised as `summary`, bytes.
fn file_bytes(summary: &[u8], solved: SolvedRef) -> u64 {
    (HEADER + summary.len() + 8 * solved.vals.len() + solved.met.len()) as u64
}

/// Writes the header and payload of `solved` (its summary serialised as `summary`) to `path`
/// in one pass: the payload's hash, known at the end, is then written into the header.
fn write_file(path: &Path, key: &Key, summary: &[u8], solved: SolvedRef) -> std::io::Result<()> {
    let mut w = BufWriter::with_capacity(CHUNK, File::create(path)?);
    w.write_all(MAGIC)?;
    w.write_all(&key.0)?;
    for n in [solved.vals.len(), solved.met.len(), summary.len()] {
        w.write_all(&(n as u64).to_le_bytes())?;
    }
    w.write_all(&[0u8; 32])?;
    let mut h = blake3::Hasher::new();
    let mut put = |bytes: &[u8]| {
        h.update(bytes);
        w.write_all(bytes)
    };
    put(summary)?;
    let mut buf = Vec::with_capacity(CHUNK);
    for chunk in solved.vals.chunks(CHUNK / 8) {
        buf.clear();
        chunk
            .iter()
            .for_each(|v| buf.extend_from_slice(&v.to_le_bytes()));
        put(&buf)?;
    }
    let flags: Vec<u8> = solved.met.iter().map(|&m| m as u8).collect();
    put(&flags)?;
    let mut file = w.into_inner().map_err(|e| e.into_error())?;
    file.seek(SeekFrom::Start((HEADER - 32) as u64))?;
    file.write_all(h.finalize().as_bytes())?;
    file.sync_all()
}

/// Reads a cache file, checking everything; None at the first thing that is not right.
fn read_checked(file: File, key: &Key, entries: usize, nodes: usize) -> Option<Solved> {
    let len = file.metadata().ok()?.len();
    let mut r = BufReader::with_capacity(CHUNK, file);
    let mut header = [0u8; HEADER];
    r.read_exact(&mut header).ok()?;
    let word = |at: usize| u64::from_le_bytes(header[at..at + 8].try_into().unwrap());
    let summary_len = word(56);
    let sizes_match = &header[..8] == MAGIC
        && header[8..40] == key.0
        && word(40) == entries as u64
        && word(48) == nodes as u64
        && len == HEADER as u64 + summary_len + 8 * entries as u64 + nodes as u64;
    if !sizes_match {
        return None;
    }
    let mut h = blake3::Hasher::new();
    let mut summary = vec![0u8; summary_len as usize];
    r.read_exact(&mut summary).ok()?;
    h.update(&summary);
    let mut vals = Vec::with_capacity(entries);
    let mut buf = vec![0u8; CHUNK];
    while vals.len() < entries {
        let n = (8 * (entries - vals.len())).min(CHUNK);
        r.read_exact(&mut buf[..n]).ok()?;
        h.update(&buf[..n]);
        vals.extend(
            buf[..n]
                .chunks_exact(8)
                .map(|b| Real::from_le_bytes(b.try_into().unwrap())),
        );
    }
    let mut flags = vec![0u8; nodes];
    r.read_exact(&mut flags).ok()?;
    h.update(&flags);
    let met: Vec<bool> = flags.iter().map(|&f| f == 1).collect();
    let intact = flags.iter().all(|&f| f <= 1)
        && h.finalize().as_bytes()[..] == header[HEADER - 32..]
        && vals.iter().all(|v| v.is_finite() && *v >= 0.0);
    let summary: Consistency = serde_json::from_slice(&summary).ok()?;
    intact.then_some(Solved { vals, met, summary })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solved() -> Solved {
        Solved {
            vals: (1..=1000).map(|i| i as f64 * 0.25).collect(),
            met: (0..40).map(|i| i % 3 != 0).collect(),
            summary: Consistency {
                newton: 4,
                ..Default::default()
            },
        }
    }

    fn cache(name: &str) -> WeightsCache {
        let dir = std::env::temp_dir().join(format!("peritherm-wc-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        WeightsCache::new(dir, 1 << 20)
    }

    #[test]
    fn a_saved_entry_loads_back_bit_for_bit() {
        let c = cache("round");
        let key = Key([7; 32]);
        c.save(&key, solved().view());
        assert_eq!(c.load(&key, 1000, 40), Some(solved()));
        assert_eq!(c.load(&Key([8; 32]), 1000, 40), None, "another key");
        assert_eq!(c.load(&key, 999, 40), None, "other counts");
        let _ = std::fs::remove_dir_all(&c.dir);
    }

    #[test]
    fn truncated_or_flipped_files_are_refused_and_removed() {
        let c = cache("corrupt");
        let key = Key([1; 32]);
        c.save(&key, solved().view());
        let path = c.path(&key);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 3]).unwrap();
        assert_eq!(c.load(&key, 1000, 40), None, "truncated");
        assert!(!path.exists(), "a truncated file is removed");
        let mut flipped = bytes.clone();
        flipped[HEADER + 200] ^= 0x10;
        std::fs::write(&path, &flipped).unwrap();
        assert_eq!(c.load(&key, 1000, 40), None, "one bit flipped");
        let _ = std::fs::remove_dir_all(&c.dir);
    }

    #[test]
    fn the_least_recently_used_files_go_first() {
        let mut c = cache("lru");
        let summary = serde_json::to_vec(&solved().summary).unwrap();
        let one = file_bytes(&summary, solved().view());
        c.max_bytes = 2 * one;
        let keys = [Key([1; 32]), Key([2; 32]), Key([3; 32])];
        c.save(&keys[0], solved().view());
        c.save(&keys[1], solved().view());
        let past = SystemTime::now() - Duration::from_secs(60);
        for (k, age) in keys[..2].iter().zip([1, 2]) {
            let f = File::options().append(true).open(c.path(k)).unwrap();
            f.set_modified(past - Duration::from_secs(age)).unwrap();
        }
        assert!(c.load(&keys[1], 1000, 40).is_some(), "used: now the newest");
        c.save(&keys[2], solved().view());
        assert!(
            !c.path(&keys[0]).exists(),
            "the least recently used is gone"
        );
        assert!(c.path(&keys[1]).exists() && c.path(&keys[2]).exists());
        c.max_bytes = one - 1;
        c.save(&Key([4; 32]), solved().view());
        assert!(
            !c.path(&Key([4; 32])).exists(),
            "larger than the cache: not kept"
        );
        let _ = std::fs::remove_dir_all(&c.dir);
    }
}
