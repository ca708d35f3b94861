//! Points and directions over the four record slots X, Y, Z, A, and the few vector
//! operations the planner uses on them.

/// A point or direction over the four record slots X, Y, Z, A.
pub type Vec4 = [f64; 4];

pub fn sub(a: Vec4, b: Vec4) -> Vec4 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]]
}
pub fn add_scaled(a: Vec4, k: f64, b: Vec4) -> Vec4 {
    [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2], a[3] + k * b[3]]
}
pub fn dot(a: Vec4, b: Vec4) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}
pub fn norm(a: Vec4) -> f64 {
    dot(a, a).sqrt()
}
pub fn scale(k: f64, a: Vec4) -> Vec4 {
    [k * a[0], k * a[1], k * a[2], k * a[3]]
}
