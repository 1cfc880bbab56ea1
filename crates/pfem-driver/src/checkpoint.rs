//! Checkpoints: the whole state of a run in a versioned binary format, so
//! that a run can stop (a crash, a kill, Ctrl-C, a wall-clock limit) and
//! continue bit for bit.
//!
//! A checkpoint is a list of named sections in one file:
//!
//! ```text
//! "PFEMCKPT"  magic, 8 bytes
//! u32         format version (FORMAT_VERSION)
//! str         library version that wrote it
//! u64         number of sections
//! (str, bytes)*  sections: name, then length-prefixed content
//! u64         FNV-1a 64 checksum of every byte before it
//! ```
//!
//! All integers and floats are little-endian; `str` and `bytes` are a `u64`
//! length then the bytes. Floats are stored as their bit patterns, so a
//! restored state is the saved one to the last bit.
//!
//! [`Simulation::checkpoint`](crate::Simulation::checkpoint) writes the
//! section [`SIMULATION`] (particles, materials, solid histories, clock,
//! volume ledger, body force, hook states) and [`TIMINGS`] (stage timers);
//! [`Simulation::restore`](crate::Simulation::restore) reads
//! them back into a simulation built from the same scene. The output layer
//! adds its own section (frames written, the probe rows' count and hash).
//! What is *not* saved: the fluid mesh (remade from the positions at the
//! next step, as every step does), the linear solver's factorisation
//! (remade), and a stop a hook asked for (a restarted run goes on).
//!
//! ```
//! use pfem_driver::checkpoint::{Checkpoint, Decoder, Encoder};
//!
//! let mut e = Encoder::new();
//! e.f64(0.1);
//! e.str("water");
//! let mut c = Checkpoint::default();
//! c.set("example", e.finish());
//! let bytes = c.encode();
//! let back = Checkpoint::decode(&bytes)?;
//! let mut d = Decoder::new(back.section("example").unwrap());
//! assert_eq!(d.f64()?.to_bits(), 0.1f64.to_bits());
//! assert_eq!(d.str()?, "water");
//! d.end()?;
//! # Ok::<(), pfem_driver::checkpoint::CheckpointError>(())
//! ```

/// The file's first eight bytes.
pub const MAGIC: &[u8; 8] = b"PFEMCKPT";

/// The format this library writes. Bumped whenever the content of a
/// section changes; a file older than [`OLDEST_FORMAT_VERSION`] or newer
/// than this is refused ([`CheckpointError::Version`]).
///
/// Version 2 (session 27): the simulation section records each material's
/// name, kind, density and wave speed, so that a scene whose material
/// changed since the checkpoint is refused.
///
/// Version 3 (session 29): and a fingerprint of each material's response
/// to two fixed probes, so that a changed viscosity, shear modulus or
/// contact stiffness is refused too.
///
/// Version 4 (session 44): the settings section records the linear
/// solver's settings ([`pfem_assembly::LinearSolver::settings`]) and the
/// alpha shape's, and a wall's motion law is kept with its hook; and
/// what a continued run computes changed since version 3 (a solid's mass
/// `ρ₀ V₀`, the interface's density, the stabilised walls' kept
/// pressures, the motion ramp).
///
/// Version 5 (session 45): the volume ledger records the drops' share of
/// the initial volume, and every fluid volume it holds counts the drops
/// in flight ([`crate::Simulation::drop_volume`]).
///
/// Version 6 (session 47): the output layer's section holds the probe
/// rows' count and hash, not the rows (they are `probes.csv`'s, since
/// session 46). A version 5 file still restores (its rows inside, or its
/// count and hash if written by session 46's library); an older library
/// given a version 6 file names the version instead of finding bytes
/// left over in the output section.
pub const FORMAT_VERSION: u32 = 6;

/// The oldest format this library reads: version 5, whose sections differ
/// from version 6's in the output layer's alone, which reads either.
pub const OLDEST_FORMAT_VERSION: u32 = 5;

/// The driver's section: the simulation state.
pub const SIMULATION: &str = "simulation";

/// The driver's section: stage timers and counters (wall time differs
/// between two runs of the same scene; the state does not).
pub const TIMINGS: &str = "timings";

/// The driver's section: its time-integration, step-control, solver and
/// driver settings, printed (session 35; a checkpoint without it is read
/// as before, unchecked).
pub const SETTINGS: &str = "settings";

/// The driver's section: which bodies take part in contact and the
/// friction between them, printed (session 36; a checkpoint without it is
/// read as before, unchecked). The penalty, damping and rounded onset are
/// the contact materials', compared with the materials.
pub const CONTACT: &str = "contact";

/// Why a checkpoint could not be read or applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// The bytes do not start with [`MAGIC`].
    #[error("not a pfem checkpoint (the file does not start with `PFEMCKPT`)")]
    NotACheckpoint,
    /// Written in a format this library does not read.
    #[error("checkpoint format {found} is not supported (this library reads formats {oldest} to {supported}; the file was written by pfem {written_by})")]
    Version {
        /// The file's format.
        found: u32,
        /// The newest format this library reads (the one it writes).
        supported: u32,
        /// The oldest format this library reads.
        oldest: u32,
        /// The library version that wrote the file.
        written_by: String,
    },
    /// The file ends early or a length runs past its end.
    #[error("checkpoint truncated: {0}")]
    Truncated(&'static str),
    /// The checksum does not match: the file was changed or damaged.
    #[error("checkpoint damaged: checksum mismatch")]
    Checksum,
    /// A value that cannot be (a kind code, a non-UTF-8 name…).
    #[error("checkpoint corrupt: {0}")]
    Corrupt(String),
    /// A section the reader needs is absent.
    #[error("checkpoint has no `{0}` section")]
    MissingSection(String),
    /// The checkpoint was written by another scene or set-up.
    #[error("checkpoint does not match this simulation, in {what}: {checkpoint} in the checkpoint, {simulation} here")]
    Mismatch {
        /// What differs.
        what: &'static str,
        /// Its value in the checkpoint.
        checkpoint: String,
        /// Its value in the simulation being restored.
        simulation: String,
    },
}

/// Appends values to a byte buffer in the checkpoint encoding
/// (little-endian, floats as bit patterns, length-prefixed strings).
#[derive(Debug, Clone, Default)]
pub struct Encoder {
    buf: Vec<u8>,
}

impl Encoder {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }
    /// One unsigned integer.
    pub fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// One float, bit for bit.
    pub fn f64(&mut self, v: f64) {
        self.buf.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    /// One boolean.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(v as u8);
    }
    /// Bytes, length first.
    pub fn bytes(&mut self, v: &[u8]) {
        self.u64(v.len() as u64);
        self.buf.extend_from_slice(v);
    }
    /// A string, length first.
    pub fn str(&mut self, v: &str) {
        self.bytes(v.as_bytes());
    }
    /// Floats, length first.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for &x in v {
            self.f64(x);
        }
    }
    /// The encoded bytes.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// A hook's fingerprint (a text that names what it prescribes: a wall's
/// motion law, a body-force ramp), read back from its saved state and
/// compared with `now`: a restart under another is refused as a
/// [`CheckpointError::Mismatch`] of `what`. An empty state, from a
/// checkpoint written before the hook saved one, is accepted unchecked
/// (a ramp's older checkpoints were refused as "truncated" by the first
/// version; a review of session 53).
pub fn restore_fingerprint(
    from: &mut Decoder<'_>,
    what: &'static str,
    now: String,
) -> Result<(), CheckpointError> {
    if from.is_at_end() {
        return Ok(());
    }
    let saved = from.str()?;
    if saved != now {
        return Err(CheckpointError::Mismatch {
            what,
            checkpoint: saved.to_string(),
            simulation: now,
        });
    }
    Ok(())
}

/// Reads values written by an [`Encoder`], in the same order.
#[derive(Debug, Clone)]
pub struct Decoder<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Decoder<'a> {
    /// Reads `buf` from its start.
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CheckpointError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.buf.len())
            .ok_or(CheckpointError::Truncated(what))?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    /// One unsigned integer.
    pub fn u64(&mut self) -> Result<u64, CheckpointError> {
        let b = self.take(8, "integer")?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    /// A count or index, checked to fit this machine and the bytes left
    /// (each counted item takes at least `min_item_bytes`).
    pub fn len(&mut self, min_item_bytes: usize) -> Result<usize, CheckpointError> {
        let n = self.u64()?;
        let left = (self.buf.len() - self.pos) as u64;
        if n.saturating_mul(min_item_bytes.max(1) as u64) > left && min_item_bytes > 0 {
            return Err(CheckpointError::Truncated("a count runs past the end"));
        }
        usize::try_from(n).map_err(|_| CheckpointError::Corrupt(format!("count {n} too large")))
    }
    /// One float.
    pub fn f64(&mut self) -> Result<f64, CheckpointError> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// One boolean.
    pub fn bool(&mut self) -> Result<bool, CheckpointError> {
        match self.take(1, "boolean")?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(CheckpointError::Corrupt(format!("boolean byte {b}"))),
        }
    }
    /// Length-prefixed bytes.
    pub fn bytes(&mut self) -> Result<&'a [u8], CheckpointError> {
        let n = self.len(1)?;
        self.take(n, "bytes")
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self) -> Result<&'a str, CheckpointError> {
        let b = self.bytes()?;
        std::str::from_utf8(b).map_err(|_| CheckpointError::Corrupt("a name is not UTF-8".into()))
    }
    /// Length-prefixed floats.
    pub fn f64s(&mut self) -> Result<Vec<f64>, CheckpointError> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    /// Whether every byte was read (a section that may end early: a field
    /// added at its end in a later version).
    pub fn is_at_end(&self) -> bool {
        self.pos == self.buf.len()
    }
    /// Fails unless every byte was read.
    pub fn end(&self) -> Result<(), CheckpointError> {
        if self.pos == self.buf.len() {
            Ok(())
        } else {
            Err(CheckpointError::Corrupt(format!(
                "{} bytes left over in a section",
                self.buf.len() - self.pos
            )))
        }
    }
}

/// A checkpoint: named sections of bytes ([module docs](self) for the
/// format).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Checkpoint {
    sections: Vec<(String, Vec<u8>)>,
}

impl Checkpoint {
    /// Sets section `name` (replacing one of that name).
    pub fn set(&mut self, name: &str, bytes: Vec<u8>) {
        match self.sections.iter_mut().find(|(n, _)| n == name) {
            Some((_, b)) => *b = bytes,
            None => self.sections.push((name.to_string(), bytes)),
        }
    }

    /// Section `name`, if present.
    pub fn section(&self, name: &str) -> Option<&[u8]> {
        self.sections
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| b.as_slice())
    }

    /// Section `name`, or [`CheckpointError::MissingSection`].
    pub fn require(&self, name: &str) -> Result<&[u8], CheckpointError> {
        self.section(name)
            .ok_or_else(|| CheckpointError::MissingSection(name.to_string()))
    }

    /// Names of the sections, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.sections.iter().map(|(n, _)| n.as_str())
    }

    /// The file's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut e = Encoder::new();
        e.buf.extend_from_slice(MAGIC);
        e.buf.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        e.str(env!("CARGO_PKG_VERSION"));
        e.u64(self.sections.len() as u64);
        for (n, b) in &self.sections {
            e.str(n);
            e.bytes(b);
        }
        let sum = fnv1a(&e.buf);
        e.u64(sum);
        e.finish()
    }

    /// Reads a checkpoint's bytes, checking magic, version and checksum.
    pub fn decode(bytes: &[u8]) -> Result<Self, CheckpointError> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(CheckpointError::NotACheckpoint);
        }
        if bytes.len() < MAGIC.len() + 4 + 8 {
            return Err(CheckpointError::Truncated("header"));
        }
        let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
        let body = &bytes[..bytes.len() - 8];
        let mut d = Decoder::new(&bytes[12..]);
        let written_by = d.str().unwrap_or("an unknown version").to_string();
        if !(OLDEST_FORMAT_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(CheckpointError::Version {
                found: version,
                supported: FORMAT_VERSION,
                oldest: OLDEST_FORMAT_VERSION,
                written_by,
            });
        }
        let sum = u64::from_le_bytes(bytes[bytes.len() - 8..].try_into().expect("8 bytes"));
        if fnv1a(body) != sum {
            return Err(CheckpointError::Checksum);
        }
        let mut d = Decoder::new(&body[12..]);
        d.str()?;
        let n = d.len(16)?;
        let mut sections = Vec::with_capacity(n);
        for _ in 0..n {
            let name = d.str()?.to_string();
            let b = d.bytes()?.to_vec();
            sections.push((name, b));
        }
        d.end()?;
        Ok(Self { sections })
    }
}

/// FNV-1a, 64 bits: detects a damaged or truncated file (not an attack).
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// A 64-bit fingerprint of some bytes (the same FNV-1a as the checksum),
/// for set-up checks such as "the same solid mesh".
pub fn fingerprint(bytes: &[u8]) -> u64 {
    fnv1a(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_detects_damage() {
        let mut c = Checkpoint::default();
        let mut e = Encoder::new();
        e.f64(-0.0);
        e.f64(f64::MIN_POSITIVE);
        e.u64(7);
        e.bool(true);
        e.f64s(&[1.0, 2.5]);
        c.set("a", e.finish());
        c.set("b", vec![]);
        let bytes = c.encode();
        let back = Checkpoint::decode(&bytes).unwrap();
        assert_eq!(back, c);
        let mut d = Decoder::new(back.section("a").unwrap());
        assert_eq!(d.f64().unwrap().to_bits(), (-0.0f64).to_bits());
        assert_eq!(d.f64().unwrap(), f64::MIN_POSITIVE);
        assert_eq!(d.u64().unwrap(), 7);
        assert!(d.bool().unwrap());
        assert_eq!(d.f64s().unwrap(), vec![1.0, 2.5]);
        d.end().unwrap();
        // Every truncation and every flipped byte is refused, never a panic.
        for cut in 0..bytes.len() {
            assert!(Checkpoint::decode(&bytes[..cut]).is_err(), "cut {cut}");
        }
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x40;
            assert!(Checkpoint::decode(&b).is_err(), "flip {i}");
        }
        // The next format, and the one before the oldest read, are
        // refused by their version (before the checksum, which covers it).
        for other in [FORMAT_VERSION + 1, OLDEST_FORMAT_VERSION - 1] {
            let mut v = bytes.clone();
            v[8..12].copy_from_slice(&other.to_le_bytes());
            let e = Checkpoint::decode(&v).unwrap_err();
            assert!(
                matches!(e, CheckpointError::Version { found, .. } if found == other),
                "{e}"
            );
            let msg = e.to_string();
            assert!(
                msg.contains(&format!(
                    "formats {OLDEST_FORMAT_VERSION} to {FORMAT_VERSION}"
                )),
                "{msg}"
            );
        }
        // Every format from the oldest read to this one's is read (its
        // checksum made for its version).
        for version in OLDEST_FORMAT_VERSION..=FORMAT_VERSION {
            let mut v = bytes[..bytes.len() - 8].to_vec();
            v[8..12].copy_from_slice(&version.to_le_bytes());
            let sum = fnv1a(&v);
            v.extend_from_slice(&sum.to_le_bytes());
            assert_eq!(Checkpoint::decode(&v).unwrap(), c, "format {version}");
        }
        assert_eq!(
            Checkpoint::decode(b"hello world, no checkpoint"),
            Err(CheckpointError::NotACheckpoint)
        );
        // A count larger than the bytes left is refused before allocating.
        let mut e = Encoder::new();
        e.u64(u64::MAX);
        assert!(Decoder::new(&e.finish()).f64s().is_err());
    }
}
