//! The family generators. Dimensions are in metres (y up, front +z) so the ranges read like
//! furniture catalogue numbers; [`Shape::new`] normalises afterwards.

use super::{Family, Op, Shape, Solid};
use crate::rng::SplitMix64;
use glam::{Mat3, Vec2, Vec3};

/// Leg styles shared by chairs and tables.
#[derive(Clone, Copy, Debug)]
enum LegStyle {
    /// Box legs.
    Square,
    /// Straight cylinders.
    Round,
    /// Cylinders narrowing towards the floor.
    Tapered,
    /// Cylinders whose feet spread outwards.
    Splayed,
}

fn add(parts: &mut Vec<(Op, Solid)>, s: Solid) {
    parts.push((Op::Union, s));
}

/// Four legs from `top_y` down to the floor under the given (x, z) corners.
fn legs(rng: &mut SplitMix64, parts: &mut Vec<(Op, Solid)>, corners: [Vec2; 4], top_y: f32, thick: f32) {
    let style = [
        LegStyle::Square,
        LegStyle::Round,
        LegStyle::Tapered,
        LegStyle::Splayed,
    ][rng.below(4)];
    let taper = rng.range(0.4, 0.8);
    let splay = rng.range(0.03, 0.1);
    for c in corners {
        let top = Vec3::new(c.x, top_y, c.y);
        let foot = Vec3::new(c.x, 0.0, c.y);
        let r = thick / 2.0;
        add(
            parts,
            match style {
                LegStyle::Square => {
                    Solid::aabb_box(foot - Vec3::new(r, 0.0, r), top + Vec3::new(r, 0.0, r))
                }
                LegStyle::Round => Solid::Frustum {
                    a: foot,
                    b: top,
                    ra: r,
                    rb: r,
                },
                LegStyle::Tapered => Solid::Frustum {
                    a: foot,
                    b: top,
                    ra: r * taper,
                    rb: r,
                },
                LegStyle::Splayed => {
                    let out = c.normalize_or_zero() * splay;
                    Solid::Frustum {
                        a: foot + Vec3::new(out.x, 0.0, out.y),
                        b: top,
                        ra: r,
                        rb: r,
                    }
                }
            },
        );
    }
}

/// Corners of a `w` x `d` rectangle inset by `inset`, as (x, z).
fn rect_corners(w: f32, d: f32, inset: f32) -> [Vec2; 4] {
    let (x, z) = (w / 2.0 - inset, d / 2.0 - inset);
    [
        Vec2::new(-x, -z),
        Vec2::new(x, -z),
        Vec2::new(-x, z),
        Vec2::new(x, z),
    ]
}

/// A chair: seat, back (solid panel, vertical or horizontal slats, possibly reclined), four
/// legs, optional arms and side stretchers.
pub fn chair(seed: u64) -> Shape {
    let mut rng = SplitMix64::new(seed, 1);
    let mut p = Vec::new();
    let (w, d) = (rng.range(0.4, 0.6), rng.range(0.38, 0.55));
    let seat_t = rng.range(0.03, 0.08);
    let seat_y = rng.range(0.38, 0.5);
    add(
        &mut p,
        Solid::aabb_box(
            Vec3::new(-w / 2.0, seat_y - seat_t, -d / 2.0),
            Vec3::new(w / 2.0, seat_y, d / 2.0),
        ),
    );
    let leg_t = rng.range(0.025, 0.055);
    let inset = rng.range(0.0, 0.04) + leg_t / 2.0;
    legs(
        &mut rng,
        &mut p,
        rect_corners(w, d, inset),
        seat_y - seat_t,
        leg_t,
    );

    // Back, built in a frame whose origin is the middle of the seat's rear top edge and which
    // is reclined about x (top towards -z).
    let back_h = rng.range(0.3, 0.55);
    let back_t = rng.range(0.02, 0.05);
    let rot = Mat3::from_rotation_x(-rng.range(0.0, 0.26));
    let origin = Vec3::new(0.0, seat_y, -d / 2.0 + back_t / 2.0);
    let mut back = |center: Vec3, half: Vec3| {
        add(
            &mut p,
            Solid::Cuboid {
                center: origin + rot * center,
                half,
                rot,
            },
        )
    };
    match rng.below(3) {
        0 => back(
            Vec3::new(0.0, back_h / 2.0, 0.0),
            Vec3::new(w / 2.0, back_h / 2.0, back_t / 2.0),
        ),
        style => {
            let post = rng.range(0.025, 0.05);
            let rail = rng.range(0.04, 0.1);
            for s in [-1.0, 1.0] {
                back(
                    Vec3::new(s * (w - post) / 2.0, back_h / 2.0, 0.0),
                    Vec3::new(post / 2.0, back_h / 2.0, back_t / 2.0),
                );
            }
            back(
                Vec3::new(0.0, back_h - rail / 2.0, 0.0),
                Vec3::new(w / 2.0, rail / 2.0, back_t / 2.0),
            );
            let slats = 2 + rng.below(4);
            let slat = rng.range(0.015, 0.04);
            for k in 0..slats {
                let f = (k as f32 + 1.0) / (slats as f32 + 1.0);
                if style == 1 {
                    let x = -w / 2.0 + post + f * (w - 2.0 * post);
                    back(
                        Vec3::new(x, back_h / 2.0, 0.0),
                        Vec3::new(slat / 2.0, back_h / 2.0, back_t / 3.0),
                    );
                } else {
                    let y = f * (back_h - rail);
                    back(
                        Vec3::new(0.0, y, 0.0),
                        Vec3::new(w / 2.0, slat / 2.0, back_t / 3.0),
                    );
                }
            }
        }
    }

    if rng.chance(0.35) {
        let arm_y = seat_y + rng.range(0.17, 0.26);
        let (arm_w, arm_t) = (rng.range(0.03, 0.07), rng.range(0.02, 0.04));
        for s in [-1.0, 1.0] {
            let x = s * (w / 2.0 - arm_w / 2.0);
            add(
                &mut p,
                Solid::aabb_box(
                    Vec3::new(x - arm_w / 2.0, arm_y - arm_t, -d / 2.0),
                    Vec3::new(x + arm_w / 2.0, arm_y, d / 2.0),
                ),
            );
            let z = d / 2.0 - arm_w;
            add(
                &mut p,
                Solid::Frustum {
                    a: Vec3::new(x, seat_y, z),
                    b: Vec3::new(x, arm_y, z),
                    ra: arm_w * 0.4,
                    rb: arm_w * 0.4,
                },
            );
        }
    }
    if rng.chance(0.4) {
        let y = rng.range(0.08, 0.2);
        let t = leg_t * 0.6;
        for c in rect_corners(w, d, inset)[..2].iter() {
            add(
                &mut p,
                Solid::Frustum {
                    a: Vec3::new(c.x, y, -c.y),
                    b: Vec3::new(c.x, y, c.y),
                    ra: t / 2.0,
                    rb: t / 2.0,
                },
            );
        }
    }
    Shape::new(Family::Chair, p)
}

/// A table: rectangular or round top on four legs or a pedestal, with an optional shelf or
/// apron.
pub fn table(seed: u64) -> Shape {
    let mut rng = SplitMix64::new(seed, 2);
    let mut p = Vec::new();
    let height = rng.range(0.65, 0.8);
    let top_t = rng.range(0.025, 0.07);
    let below = height - top_t;
    if rng.chance(0.3) {
        let r = rng.range(0.4, 0.7);
        add(
            &mut p,
            Solid::Frustum {
                a: Vec3::new(0.0, below, 0.0),
                b: Vec3::new(0.0, height, 0.0),
                ra: r,
                rb: r,
            },
        );
        let col = rng.range(0.04, 0.1);
        add(
            &mut p,
            Solid::Frustum {
                a: Vec3::ZERO,
                b: Vec3::new(0.0, below, 0.0),
                ra: col,
                rb: col,
            },
        );
        let foot = rng.range(0.25, 0.9) * r;
        add(
            &mut p,
            Solid::Frustum {
                a: Vec3::ZERO,
                b: Vec3::new(0.0, rng.range(0.02, 0.05), 0.0),
                ra: foot,
                rb: foot * 0.8,
            },
        );
    } else {
        let (w, d) = (rng.range(0.8, 1.6), rng.range(0.5, 1.0));
        add(
            &mut p,
            Solid::aabb_box(
                Vec3::new(-w / 2.0, below, -d / 2.0),
                Vec3::new(w / 2.0, height, d / 2.0),
            ),
        );
        let leg_t = rng.range(0.035, 0.08);
        let inset = rng.range(0.0, 0.1) + leg_t / 2.0;
        legs(&mut rng, &mut p, rect_corners(w, d, inset), below, leg_t);
        let (x, z) = (w / 2.0 - inset, d / 2.0 - inset);
        if rng.chance(0.35) {
            let y = rng.range(0.1, 0.25);
            add(
                &mut p,
                Solid::aabb_box(
                    Vec3::new(-x, y, -z),
                    Vec3::new(x, y + rng.range(0.015, 0.03), z),
                ),
            );
        } else if rng.chance(0.5) {
            let apron = rng.range(0.05, 0.12);
            let t = leg_t * 0.4;
            for s in [-1.0, 1.0] {
                add(
                    &mut p,
                    Solid::aabb_box(
                        Vec3::new(-x, below - apron, s * z - t),
                        Vec3::new(x, below, s * z + t),
                    ),
                );
                add(
                    &mut p,
                    Solid::aabb_box(
                        Vec3::new(s * x - t, below - apron, -z),
                        Vec3::new(s * x + t, below, z),
                    ),
                );
            }
        }
    }
    Shape::new(Family::Table, p)
}

/// A sofa: base block, one to three seat cushions, back, two arms (square or rolled), and
/// optional short feet.
pub fn sofa(seed: u64) -> Shape {
    let mut rng = SplitMix64::new(seed, 3);
    let mut p = Vec::new();
    let (w, d) = (rng.range(1.4, 2.2), rng.range(0.75, 0.95));
    let foot_h = if rng.chance(0.6) {
        rng.range(0.04, 0.12)
    } else {
        0.0
    };
    let base_top = rng.range(0.25, 0.35);
    let (arm_w, back_t) = (rng.range(0.1, 0.25), rng.range(0.15, 0.25));
    add(
        &mut p,
        Solid::aabb_box(
            Vec3::new(-w / 2.0, foot_h, -d / 2.0),
            Vec3::new(w / 2.0, base_top, d / 2.0),
        ),
    );
    let cushions = 1 + rng.below(3);
    let cush_t = rng.range(0.08, 0.15);
    let inner = w - 2.0 * arm_w;
    let gap = 0.01;
    for k in 0..cushions {
        let x0 = -inner / 2.0 + inner * k as f32 / cushions as f32 + gap;
        let x1 = -inner / 2.0 + inner * (k + 1) as f32 / cushions as f32 - gap;
        add(
            &mut p,
            Solid::aabb_box(
                Vec3::new(x0, base_top, -d / 2.0 + back_t),
                Vec3::new(x1, base_top + cush_t, d / 2.0),
            ),
        );
    }
    let seat_y = base_top + cush_t;
    let back_top = seat_y + rng.range(0.3, 0.5);
    add(
        &mut p,
        Solid::aabb_box(
            Vec3::new(-w / 2.0, base_top, -d / 2.0),
            Vec3::new(w / 2.0, back_top, -d / 2.0 + back_t),
        ),
    );
    let arm_top = seat_y + rng.range(0.1, 0.3);
    let rolled = rng.chance(0.4);
    for s in [-1.0f32, 1.0] {
        let (x0, x1) = (s * w / 2.0, s * (w / 2.0 - arm_w));
        let (lo, hi) = (x0.min(x1), x0.max(x1));
        let top = if rolled {
            arm_top - arm_w / 2.0
        } else {
            arm_top
        };
        add(
            &mut p,
            Solid::aabb_box(
                Vec3::new(lo, base_top, -d / 2.0),
                Vec3::new(hi, top, d / 2.0),
            ),
        );
        if rolled {
            let (c, r) = ((lo + hi) / 2.0, arm_w / 2.0);
            add(
                &mut p,
                Solid::Frustum {
                    a: Vec3::new(c, top, -d / 2.0),
                    b: Vec3::new(c, top, d / 2.0),
                    ra: r,
                    rb: r,
                },
            );
        }
    }
    if foot_h > 0.0 {
        let r = rng.range(0.02, 0.04);
        for c in rect_corners(w, d, r + 0.03) {
            add(
                &mut p,
                Solid::Frustum {
                    a: Vec3::new(c.x, 0.0, c.y),
                    b: Vec3::new(c.x, foot_h, c.y),
                    ra: r * 0.8,
                    rb: r,
                },
            );
        }
    }
    Shape::new(Family::Sofa, p)
}

/// A random solid (box, sphere or cylinder) of size about `size` near the origin.
fn random_solid(rng: &mut SplitMix64, size: f32, spread: f32) -> Solid {
    let center = Vec3::new(
        rng.range(-spread, spread),
        rng.range(-spread, spread),
        rng.range(-spread, spread),
    );
    let rot = Mat3::from_euler(
        glam::EulerRot::YXZ,
        rng.range(0.0, 3.2),
        rng.range(-0.8, 0.8),
        rng.range(-0.8, 0.8),
    );
    match rng.below(3) {
        0 => {
            let half = Vec3::new(
                rng.range(0.3, 1.0),
                rng.range(0.3, 1.0),
                rng.range(0.3, 1.0),
            ) * size;
            Solid::Cuboid { center, half, rot }
        }
        1 => Solid::Sphere {
            center,
            radius: rng.range(0.5, 1.0) * size,
        },
        _ => {
            let axis = rot * Vec3::Y * rng.range(0.4, 1.0) * size;
            let r = rng.range(0.25, 0.7) * size;
            Solid::Frustum {
                a: center - axis,
                b: center + axis,
                ra: r,
                rb: r,
            }
        }
    }
}

/// One to three unioned solids with up to two smaller solids carved out of them.
pub fn primitive(seed: u64) -> Shape {
    let mut rng = SplitMix64::new(seed, 4);
    let mut p = Vec::new();
    for k in 0..1 + rng.below(3) {
        let spread = if k == 0 { 0.0 } else { 0.5 };
        add(&mut p, random_solid(&mut rng, 1.0, spread));
    }
    for _ in 0..rng.below(3) {
        // Smaller and off-centre, so a carve never removes the whole shape.
        let mut s = random_solid(&mut rng, 0.45, 0.6);
        if let Solid::Sphere { center, .. } | Solid::Cuboid { center, .. } = &mut s
            && center.length() < 0.3
        {
            *center += Vec3::X * 0.5;
        }
        p.push((Op::Difference, s));
    }
    Shape::new(Family::Primitive, p)
}
