//! TEMPORARY stub (replaced by the shapes branch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    pub gap: f64,
    pub normal: [f64; 3],
    pub point: [f64; 3],
    pub tangents: [[f64; 3]; 2],
    pub hessian: [[f64; 3]; 3],
}
pub trait Shape: std::fmt::Debug + Send + Sync {
    fn project(&self, x: [f64; 3]) -> Option<Projection>;
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>);
    fn kind(&self) -> &'static str;
}
#[derive(Debug)]
pub struct Plane {
    pub display_size: f64,
}
#[derive(Debug)]
pub struct FinitePlane {
    pub lx: f64,
    pub ly: f64,
}
#[derive(Debug)]
pub struct Cylinder {
    pub radius: f64,
    pub length: f64,
}
#[derive(Debug)]
pub struct Sphere {
    pub radius: f64,
}
#[derive(Debug)]
pub struct Prism {
    pub size: [f64; 3],
}
impl Shape for Plane {
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        Some(Projection {
            gap: x[2],
            normal: [0., 0., 1.],
            point: [x[0], x[1], 0.],
            tangents: [[1., 0., 0.], [0., 1., 0.]],
            hessian: [[0.; 3]; 3],
        })
    }
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (vec![], vec![])
    }
    fn kind(&self) -> &'static str {
        "plane"
    }
}
impl Shape for Sphere {
    fn project(&self, x: [f64; 3]) -> Option<Projection> {
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        let n = [x[0] / r, x[1] / r, x[2] / r];
        let a = if n[2].abs() > 0.9 {
            [1., 0., 0.]
        } else {
            [0., 0., 1.]
        };
        let c = [
            a[1] * n[2] - a[2] * n[1],
            a[2] * n[0] - a[0] * n[2],
            a[0] * n[1] - a[1] * n[0],
        ];
        let cn = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        let t1 = [c[0] / cn, c[1] / cn, c[2] / cn];
        let t2 = [
            n[1] * t1[2] - n[2] * t1[1],
            n[2] * t1[0] - n[0] * t1[2],
            n[0] * t1[1] - n[1] * t1[0],
        ];
        let mut h = [[0.; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                h[i][j] = ((i == j) as u8 as f64 - n[i] * n[j]) / r;
            }
        }
        Some(Projection {
            gap: r - self.radius,
            normal: n,
            point: [n[0] * self.radius, n[1] * self.radius, n[2] * self.radius],
            tangents: [t1, t2],
            hessian: h,
        })
    }
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (vec![], vec![])
    }
    fn kind(&self) -> &'static str {
        "sphere"
    }
}
impl Shape for FinitePlane {
    fn project(&self, _x: [f64; 3]) -> Option<Projection> {
        None
    }
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (vec![], vec![])
    }
    fn kind(&self) -> &'static str {
        "finite-plane"
    }
}
impl Shape for Cylinder {
    fn project(&self, _x: [f64; 3]) -> Option<Projection> {
        None
    }
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (vec![], vec![])
    }
    fn kind(&self) -> &'static str {
        "cylinder"
    }
}
impl Shape for Prism {
    fn project(&self, _x: [f64; 3]) -> Option<Projection> {
        None
    }
    fn surface(&self) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        (vec![], vec![])
    }
    fn kind(&self) -> &'static str {
        "prism"
    }
}
