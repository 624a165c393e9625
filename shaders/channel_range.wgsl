// Indexing a channel range: channels c0 .. c0 + cp of a tensor [N, C, S] (S the product of
// the spatial axes). Prepended to concat.wgsl (a part of a concatenation, a narrowed range)
// and sigmoid.wgsl (the sigmoid of a range read in place).

// The uniform block of the kernels that use these helpers (`concat::Params` in Rust): n items,
// a part or range of cp channels at channel c0 of a whole of cy, s values a channel.
struct ChannelRange { n: u32, cp: u32, cy: u32, s: u32, c0: u32 }

// Index in the whole [N, C, S] of element i of the range [N, cp, S].
fn range_to_whole(i: u32, s: u32, cp: u32, c: u32, c0: u32) -> u32 {
    let si = i % s;
    let ch = (i / s) % cp;
    let n = i / (s * cp);
    return (n * c + c0 + ch) * s + si;
}

// Element j of the whole: whether it lies in the range, and its index in the range (where it
// does not, a valid index whose value the caller drops).
struct InRange { inside: bool, i: u32 }

fn whole_to_range(j: u32, s: u32, cp: u32, c: u32, c0: u32) -> InRange {
    let ch = (j / s) % c;
    let inside = ch >= c0 && ch < c0 + cp;
    return InRange(inside, ((j / (s * c)) * cp + select(0u, ch - c0, inside)) * s + j % s);
}
