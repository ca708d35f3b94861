//! The exact-geometry ideals of the point-by-point comparison interpolator's tests
//! (integers only, no model helper): shared by `pbp_interp.rs` (the block) and
//! `core_pbp.rs` (the block in the core), each using what it needs.
#![allow(dead_code)]

/// `|sqrt(r2) - sqrt(big_r2)| <= 1`, exactly: `r <= R + 1` and `r >= R - 1` squared.
pub fn within_one_of_circle(r2: i128, big_r2: i128) -> bool {
    // r <= R + 1  <=>  r2 - R2 - 1 <= 2R  <=>  d <= 0 or d^2 <= 4 R2.
    let d = r2 - big_r2 - 1;
    let outer = d <= 0 || d * d <= 4 * big_r2;
    // r >= R - 1  <=>  R2 + 1 - r2 <= 2R  <=>  e <= 0 or e^2 <= 4 R2.
    let e = big_r2 + 1 - r2;
    let inner = e <= 0 || e * e <= 4 * big_r2;
    outer && inner
}

/// Whether `(x, y)` (relative to the start) is within one step of the segment from the
/// origin to `(xe, ye)`: inside the segment's box, and `|xe*y - ye*x| / L <= 1`
/// (in the box the nearest point of the line lies on the segment).
pub fn within_one_of_segment(xe: i64, ye: i64, x: i64, y: i64) -> bool {
    let cross = xe as i128 * y as i128 - ye as i128 * x as i128;
    let l2 = (xe as i128).pow(2) + (ye as i128).pow(2);
    let in_box = (x == 0 || x.signum() == xe.signum())
        && x.abs() <= xe.abs()
        && (y == 0 || y.signum() == ye.signum())
        && y.abs() <= ye.abs();
    in_box && cross * cross <= l2
}
