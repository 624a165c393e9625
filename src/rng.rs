//! The crate's one seeded generator. Datasets, parameter initialisation, training's sample
//! order and the kernel tests all draw from it, so their bytes depend on nothing but seeds
//! (`tests/rng.rs` pins its outputs).

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, statistically fine for shapes, inits
/// and sampling, and stable across platforms and crate versions, which `rand` would not
/// promise. The field is the whole state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

/// Multiplier mixing a stream number into a seed (`SplitMix64::keyed`).
const STREAM_KEY: u64 = 0xD1B5_4A32_D192_ED03;
/// SplitMix64's state increment (the golden ratio in 64 bits); also salts one-shot hashes.
pub(crate) const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;
/// The output mix's first multiplier.
pub(crate) const MIX1: u64 = 0xBF58_476D_1CE4_E5B9;
/// The output mix's second multiplier.
pub(crate) const MIX2: u64 = 0x94D0_49BB_1331_11EB;

impl SplitMix64 {
    /// The generator with state `seed ^ stream * K`: one seed, many unrelated streams.
    pub fn keyed(seed: u64, stream: u64) -> Self {
        SplitMix64(seed ^ stream.wrapping_mul(STREAM_KEY))
    }

    /// [`SplitMix64::keyed`] with its first output dropped, which decorrelates nearby seeds
    /// (the shape and dataset streams).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self::keyed(seed, stream);
        r.next_u64();
        r
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GAMMA);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(MIX1);
        z = (z ^ (z >> 27)).wrapping_mul(MIX2);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[0, 1)` with 24 random bits.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }

    /// Uniform integer in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}
