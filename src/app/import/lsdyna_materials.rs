//! LS-DYNA materials as alfe materials: `*MAT_ELASTIC`, `*MAT_MOONEY-RIVLIN_RUBBER`,
//! `*MAT_HYPERELASTIC_RUBBER` (C10, C01), `*MAT_PIECEWISE_LINEAR_PLASTICITY`,
//! `*MAT_PLASTIC_KINEMATIC` (isotropic hardening), with their `_TITLE` forms.

use super::keyword_blocks::Block;

/// A translated material: its LS-DYNA number and name, its TOML body (`@LCSS` where the
/// hardening table comes from curve `lcss`), the modulus that labels the deck's units,
/// and what was not translated.
pub struct Mat {
    pub mid: i64,
    pub name: String,
    pub body: String,
    pub modulus: f64,
    pub lcss: Option<i64>,
    pub notes: Vec<String>,
}

/// The plastic hardening modulus h of a tangent modulus ETAN: E ETAN / (E − ETAN).
fn tangent_to_plastic(e: f64, et: f64, b: &Block) -> Result<f64, String> {
    if !(0.0..e).contains(&et) {
        return Err(format!("{}: ETAN = {et} must lie in [0, E = {e})", b.at()));
    }
    Ok(e * et / (e - et))
}

/// A `*MAT_*` card as an alfe material; Ok(Err(why)) for a material type not
/// translated.
pub fn material(b: &Block) -> Result<Result<Mat, String>, String> {
    let mut notes = Vec::new();
    let titled = b.kw.ends_with("_TITLE");
    let base = b.kw.trim_end_matches("_TITLE");
    let c0 = usize::from(titled);
    let named = |mid: i64| {
        titled
            .then(|| b.data[0].text.trim().to_string())
            .filter(|s| !s.is_empty())
            .unwrap_or(format!("mat-{mid}"))
    };
    b.need(c0 + 1)?;
    let mid = b.int(c0, 0)?;
    let ro = b.real(c0, 1)?;
    let mut lcss = None;
    let density = if ro > 0.0 {
        format!("density = {ro:e}\n")
    } else {
        String::new()
    };
    let (body, modulus) = match base {
        "MAT_ELASTIC" | "MAT_001" => {
            let (e, nu) = (b.real(c0, 2)?, b.real(c0, 3)?);
            (
                format!("model = \"linear-elastic\"\nE = {e:e}\nnu = {nu}\n"),
                e,
            )
        }
        "MAT_MOONEY-RIVLIN_RUBBER" | "MAT_027" => {
            let (nu, a, bb) = (b.real(c0, 2)?, b.real(c0, 3)?, b.real(c0, 4)?);
            (
                format!("model = \"mooney-rivlin\"\nC10 = {a:e}\nC01 = {bb:e}\nnu = {nu}\n"),
                6.0 * (a + bb),
            )
        }
        "MAT_HYPERELASTIC_RUBBER" | "MAT_077_H" => {
            b.need(c0 + 2)?;
            let (nu, n) = (b.real(c0, 2)?, b.int(c0, 3)?);
            if n != 0 {
                notes.push("N > 0 (constants fitted from test data) is not translated: C10, C01 of card 2 are used".into());
            }
            let (c10, c01) = (b.real(c0 + 1, 0)?, b.real(c0 + 1, 1)?);
            if (2..6).any(|j| b.real(c0 + 1, j).is_ok_and(|v| v != 0.0)) {
                notes.push(
                    "C11, C20, C02, C30 are not translated (Mooney–Rivlin from C10, C01)".into(),
                );
            }
            if c01 == 0.0 {
                let mu = 2.0 * c10;
                let e = 2.0 * mu * (1.0 + nu);
                (
                    format!("model = \"neo-hookean\"\nE = {e:e}\nnu = {nu}\n"),
                    e,
                )
            } else {
                (
                    format!("model = \"mooney-rivlin\"\nC10 = {c10:e}\nC01 = {c01:e}\nnu = {nu}\n"),
                    6.0 * (c10 + c01),
                )
            }
        }
        "MAT_PIECEWISE_LINEAR_PLASTICITY" | "MAT_024" => {
            let (body, e, l) = plasticity(b, c0, &mut notes)?;
            lcss = l;
            (body, e)
        }
        "MAT_PLASTIC_KINEMATIC" | "MAT_003" => {
            let (e, nu, sy, et, beta) = (
                b.real(c0, 2)?,
                b.real(c0, 3)?,
                b.real(c0, 4)?,
                b.real(c0, 5)?,
                b.real(c0, 6)?,
            );
            if beta != 1.0 {
                notes.push(format!(
                    "BETA = {beta}: kinematic hardening is not modelled; taken as isotropic"
                ));
            }
            let h = tangent_to_plastic(e, et, b)?;
            (format!("model = \"j2\"\nE = {e:e}\nnu = {nu}\nyield_stress = {sy:e}\nhardening = {{ type = \"linear\", modulus = {h:e} }}\n"), e)
        }
        _ => return Ok(Err("material type not translated".into())),
    };
    Ok(Ok(Mat {
        mid,
        name: named(mid),
        body: format!("{body}{density}"),
        modulus,
        lcss,
        notes,
    }))
}

/// `*MAT_PIECEWISE_LINEAR_PLASTICITY`: the LCSS curve (ε̄p, σy), else the EPS/ES table,
/// else SIGY with ETAN (h = E ETAN / (E − ETAN)).
fn plasticity(
    b: &Block,
    c0: usize,
    notes: &mut Vec<String>,
) -> Result<(String, f64, Option<i64>), String> {
    let (e, nu, sy, et) = (
        b.real(c0, 2)?,
        b.real(c0, 3)?,
        b.real(c0, 4)?,
        b.real(c0, 5)?,
    );
    let (c, p, lcss) = (b.real(c0 + 1, 0)?, b.real(c0 + 1, 1)?, b.int(c0 + 1, 2)?);
    if c != 0.0 || p != 0.0 {
        notes.push("strain-rate effects (C, P) are not modelled".into());
    }
    let head = format!("model = \"j2\"\nE = {e:e}\nnu = {nu}\n");
    if let (Some(h), true) = (b.note("hardening"), lcss > 0) {
        // alfe's own law (a power law), whose table LCSS is LS-DYNA's copy.
        return Ok((format!("{head}@LCSS\nhardening = {h}\n"), e, Some(lcss)));
    }
    if lcss > 0 {
        return Ok((format!("{head}@LCSS\n"), e, Some(lcss)));
    }
    let eps: Vec<f64> = (0..8)
        .map(|j| b.real(c0 + 2, j))
        .collect::<Result<_, _>>()?;
    let es: Vec<f64> = (0..8)
        .map(|j| b.real(c0 + 3, j))
        .collect::<Result<_, _>>()?;
    let pts: Vec<String> = eps
        .iter()
        .zip(&es)
        .enumerate()
        .filter(|(j, (_, s))| *j == 0 || **s != 0.0)
        .map(|(_, (a, s))| format!("[{a:e}, {s:e}]"))
        .collect();
    if es[0] != 0.0 {
        return Ok((
            format!(
                "{head}yield_stress = {:e}\nhardening = {{ type = \"table\", points = [{}] }}\n",
                es[0],
                pts.join(", ")
            ),
            e,
            None,
        ));
    }
    let h = tangent_to_plastic(e, et, b)?;
    Ok((
        format!(
            "{head}yield_stress = {sy:e}\nhardening = {{ type = \"linear\", modulus = {h:e} }}\n"
        ),
        e,
        None,
    ))
}
