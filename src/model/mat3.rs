//! 3×3 algebra of the model's rigid-body pieces (distributing couplings, contact
//! entities, walls): skew matrices, products, and the flattening of a block for the
//! distributed matrix.

pub type M3 = [[f64; 3]; 3];

pub fn skew(d: [f64; 3]) -> M3 {
    [[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]]
}

pub fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

pub fn add(a: &M3, b: &M3, s: f64) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] + s * b[i][j]))
}

pub fn flat(a: &M3, s: f64) -> [f64; 9] {
    std::array::from_fn(|k| s * a[k / 3][k % 3])
}

/// a × b on the model's arrays, by nalgebra (the same products and differences as a
/// hand-written cross product: bit for bit).
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    nalgebra::Vector3::from(a)
        .cross(&nalgebra::Vector3::from(b))
        .into()
}

pub const ID: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

pub fn transpose(a: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}
