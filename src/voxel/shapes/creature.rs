//! The creature family: curved, animal-like bodies, the surfaces furniture lacks (the real
//! meshes of `datasets/` are mostly animals, heads and chairs). Units as in
//! [`super::families`]: y up, front +z, the floor at y = 0.

use super::{Family, Op, Shape, Solid};
use crate::rng::SplitMix64;
use glam::{EulerRot, Mat3, Vec3};

fn ellipsoid(center: Vec3, radii: Vec3, rot: Mat3) -> (Op, Solid) {
    (Op::Union, Solid::Ellipsoid { center, radii, rot })
}

fn limb(a: Vec3, b: Vec3, ra: f32, rb: f32) -> (Op, Solid) {
    (Op::Union, Solid::Frustum { a, b, ra, rb })
}

/// A creature for `seed`: three in four an animal (an ellipsoid body on 0, 2 or 4 legs, with
/// a neck, a head and maybe a tail, ears or a snout), else a cluster of 3-7 ellipsoids.
pub fn creature(seed: u64) -> Shape {
    let mut rng = SplitMix64::new(seed, 6);
    if rng.chance(0.25) {
        return Shape::new(Family::Creature, cluster(&mut rng));
    }
    let mut p = Vec::new();
    // Body along z (front +z), raised on its legs.
    let (len, height, width) = (rng.range(0.3, 0.6), rng.range(0.15, 0.3), rng.range(0.12, 0.28));
    let legs = [0, 2, 4, 4][rng.below(4)];
    let pitch = if legs == 2 { rng.range(-1.2, -0.5) } else { rng.range(-0.2, 0.2) };
    // Legs long enough that the pitched body's lowest point stays above the feet.
    let dip = ((height * pitch.cos()).hypot(len * pitch.sin()) - 0.8 * height).max(0.0);
    let leg_h = if legs == 0 { 0.0 } else { rng.range(0.15, 0.6).max(dip + 0.05) };
    let body_rot = Mat3::from_rotation_x(pitch);
    let body = Vec3::new(0.0, leg_h + height * 0.8, 0.0);
    p.push(ellipsoid(body, Vec3::new(width, height, len), body_rot));
    let leg_r = rng.range(0.03, 0.08);
    let spread = rng.range(0.5, 0.9);
    let feet: &[(f32, f32)] = match legs {
        2 => &[(-1.0, 0.0), (1.0, 0.0)],
        4 => &[(-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)],
        _ => &[],
    };
    for &(sx, sz) in feet {
        let hip = body + Vec3::new(sx * width * 0.6, -height * 0.3, sz * len * spread * 0.8);
        let foot = Vec3::new(hip.x * rng.range(1.0, 1.3), 0.0, hip.z + rng.range(-0.05, 0.05));
        p.push(limb(foot, hip, leg_r * rng.range(0.6, 1.0), leg_r));
    }
    // Neck from the body's front (its top for a biped) to the head.
    let front = body + body_rot * Vec3::new(0.0, height * 0.3, len * 0.8);
    let neck_dir = Vec3::new(0.0, rng.range(0.2, 1.5), rng.range(0.2, 1.0)).normalize();
    let neck_len = rng.range(0.0, 0.5);
    let head = front + neck_dir * neck_len;
    let head_r = rng.range(0.08, 0.2);
    if neck_len > 0.05 {
        p.push(limb(front, head, rng.range(0.04, 0.1), rng.range(0.03, 0.06)));
    }
    let head_rot = Mat3::from_rotation_x(rng.range(-0.6, 0.6));
    p.push(ellipsoid(head, Vec3::new(head_r, head_r * rng.range(0.7, 1.1), head_r * rng.range(1.0, 1.8)), head_rot));
    if rng.chance(0.5) {
        // A snout or a trunk.
        let tip = head + Vec3::new(0.0, rng.range(-0.3, 0.05), rng.range(0.1, 0.35));
        p.push(limb(head, tip, head_r * 0.5, head_r * rng.range(0.15, 0.4)));
    }
    if rng.chance(0.5) {
        let ear = Vec3::new(head_r * 0.7, head_r * rng.range(0.5, 1.0), 0.0);
        let r = Vec3::new(head_r * 0.15, head_r * rng.range(0.3, 0.8), head_r * rng.range(0.2, 0.6));
        for s in [-1.0f32, 1.0] {
            p.push(ellipsoid(head + ear * Vec3::new(s, 1.0, 1.0), r, Mat3::from_rotation_z(-s * 0.4)));
        }
    }
    if rng.chance(0.6) {
        let root = body + body_rot * Vec3::new(0.0, 0.0, -len * 0.9);
        let tip = root + Vec3::new(rng.range(-0.1, 0.1), rng.range(-0.3, 0.3), -rng.range(0.15, 0.5));
        p.push(limb(root, tip, rng.range(0.02, 0.06), rng.range(0.005, 0.03)));
    }
    Shape::new(Family::Creature, p)
}

/// 3-7 ellipsoids, each centred inside one placed before it (so the cluster is one piece).
fn cluster(rng: &mut SplitMix64) -> Vec<(Op, Solid)> {
    let mut parts: Vec<(Vec3, Vec3, Mat3)> = Vec::new();
    for k in 0..3 + rng.below(5) {
        let size = if k == 0 { 1.0 } else { rng.range(0.3, 0.8) };
        let radii = Vec3::new(rng.range(0.3, 1.0), rng.range(0.3, 1.0), rng.range(0.3, 1.0)) * size * 0.5;
        let rot = Mat3::from_euler(EulerRot::YXZ, rng.range(0.0, 3.2), rng.range(-0.8, 0.8), rng.range(-0.8, 0.8));
        let center = if parts.is_empty() {
            Vec3::ZERO
        } else {
            let (c, r, q) = parts[rng.below(parts.len())];
            let dir = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).normalize_or(Vec3::X);
            // The parent's surface lies `1 / |diag(1 / r) q^T dir|` from its centre along `dir`.
            let reach = 1.0 / ((q.transpose() * dir) / r).length();
            c + dir * reach * rng.range(0.5, 0.95)
        };
        parts.push((center, radii, rot));
    }
    parts.into_iter().map(|(c, r, q)| ellipsoid(c, r, q)).collect()
}
