//! The outer medium of a container scene (`[chain] outer = { medium = .. }`): what lies beyond
//! its outer chains, which the leaked waves run into and which presses back on the container.
//! [`apply`] rewrites the parsed file before it is checked, following the container contract
//! of `scenes/containers/` (sections `outer-left` first, `outer-right`, `striker`,
//! `beyond-striker` last). A sweep file's `containers[i].outer` applies the same edit.

use super::file::{ContactDampingFile, EndFile, SceneFile, SectionFile};

/// The type lives in `file.rs` with the rest of the schema (the file's `[chain] outer` holds
/// one); its meaning, the edit, is here.
pub use super::file::OuterMedium;

impl OuterMedium {
    /// The medium with its numbers, in words (`free ends at 300`; no commas, for CSV cells).
    pub fn label(&self) -> String {
        match *self {
            OuterMedium::Long => "long".into(),
            OuterMedium::FreeEnds { distance } => format!("free ends at {distance}"),
            OuterMedium::GroundDamped {
                distance,
                layer,
                rate,
            } => format!("ground-damped at {distance} ({layer} grains; rate {rate})"),
            OuterMedium::Dashpot { distance, layer, c } => {
                format!("dashpot at {distance} ({layer} grains; c {c})")
            }
        }
    }

    /// Whether the chain has ends that waves reach (every medium but `long`).
    pub fn has_ends(&self) -> bool {
        !matches!(self, OuterMedium::Long)
    }

    /// Whether the medium damps (then the scene runs blanes-moan4 single rate: the multirate
    /// method applies no damping).
    pub fn damps(&self) -> bool {
        matches!(
            self,
            OuterMedium::GroundDamped { .. } | OuterMedium::Dashpot { .. }
        )
    }

    /// What is wrong with the medium's numbers, if anything (the caller names the key).
    pub fn problem(&self) -> Option<String> {
        let (distance, layer, coefficient) = match *self {
            OuterMedium::Long => return None,
            OuterMedium::FreeEnds { distance } => (distance, 1, 1.0),
            OuterMedium::GroundDamped {
                distance,
                layer,
                rate,
            } => (distance, layer, rate),
            OuterMedium::Dashpot { distance, layer, c } => (distance, layer, c),
        };
        if !(MIN_DISTANCE..=1_000_000).contains(&distance) {
            return Some(format!(
                "distance must be between {MIN_DISTANCE} (the grains from the container to the striker and one more) and 1e6 grains (got {distance})"
            ));
        }
        if !(1..=1_000_000).contains(&layer) {
            return Some(format!(
                "layer must be between 1 and 1e6 grains (got {layer})"
            ));
        }
        if !(coefficient.is_finite() && coefficient > 0.0) {
            let name = if matches!(self, OuterMedium::Dashpot { .. }) {
                "c"
            } else {
                "rate"
            };
            return Some(format!(
                "{name} must be a positive number (got {coefficient})"
            ));
        }
        None
    }
}

/// What is wrong with the file's method for `medium`, if anything: a damped medium needs a
/// method that applies damping, and the file's own method (`integrator.method`, multirate by
/// default in the container scenes) is refused under `chain.outer`, the key the user wrote,
/// naming the method's key (not the generated layer's `contact_damping`). Switching the
/// method silently would change what the file says. (A sweep's `outer` switches it: there the
/// container's medium is the more specific setting: `batch::Stepping::decide`.)
pub fn method_problem(f: &SceneFile, medium: OuterMedium) -> Option<String> {
    if !medium.damps() {
        return None;
    }
    let i = f.integrator.as_ref();
    let method = i
        .and_then(|i| i.method)
        .unwrap_or(crate::IntegrationParams::default().method);
    let info = method.information();
    if info.damping {
        return None;
    }
    Some(format!(
        "a damped outer medium ({}) needs a method that applies damping ({}), but \
         `integrator.method` is {}{}",
        medium.label(),
        crate::Method::names_with(|i| i.damping, "or"),
        info.name,
        if i.is_some_and(|i| i.multirate.is_some()) {
            " (with `integrator.multirate`)"
        } else {
            ""
        }
    ))
}

/// The smallest `distance` of an outer medium: the container contract's `outer-right` (120
/// grains), the striker and one grain beyond it.
pub const MIN_DISTANCE: u64 = 122;

/// Add `shift` to every grain number of the regions, initial conditions and snapshot range
/// (grains were added or removed on the left). Saturating: a number so far out that it would
/// wrap stays far outside the chain, where the scene check reports it.
pub fn shift_grains(f: &mut SceneFile, shift: i64) {
    for r in f.regions.iter_mut() {
        r.first = r.first.saturating_add(shift);
        r.last = r.last.saturating_add(shift);
    }
    for g in f.initial.iter_mut() {
        for x in [&mut g.grain, &mut g.first, &mut g.last]
            .into_iter()
            .flatten()
        {
            *x = x.saturating_add(shift);
        }
    }
    // The snapshot range is in the same grain numbers as the regions: left where it was, it
    // would silently record other grains once the outer chains are cut.
    if let Some(s) = f.output.as_mut().and_then(|o| o.snapshots.as_mut()) {
        for x in [&mut s.first, &mut s.last].into_iter().flatten() {
            *x = x.saturating_add(shift);
        }
    }
}

/// Surround the container with `medium`: `outer-left` gets `distance` grains and
/// `beyond-striker` the rest of `distance` on the right (every grain number shifts with
/// `outer-left`); both ends become free; a damped layer is a section like `beyond-striker`
/// added at each end (`layer-left`, `layer-right`). Returns how far every grain number moved
/// (added to the file's numbers: errors about them subtract it again, so they show the numbers
/// the file wrote). Errors: the message of what is wrong (the caller names the key).
///
/// The medium ends the chain with free ends, so a wall the file puts at an end of the chain is
/// refused, naming it: a researcher who wrote both a wall and a medium beyond it meant one of
/// the two, and neither silently replacing the wall nor keeping it behind the medium is what
/// they asked for.
pub fn apply(f: &mut SceneFile, medium: OuterMedium) -> Result<i64, String> {
    let (distance, layer) = match medium {
        OuterMedium::Long => return Ok(0),
        OuterMedium::FreeEnds { distance } => (distance, None),
        OuterMedium::GroundDamped {
            distance,
            layer,
            rate,
        } => (distance, Some((layer, Some(rate), None))),
        OuterMedium::Dashpot { distance, layer, c } => (
            distance,
            Some((
                layer,
                None,
                Some(ContactDampingFile {
                    model: crate::chain::DampingModel::Viscous,
                    c,
                }),
            )),
        ),
    };
    if let Some(problem) = medium.problem() {
        return Err(problem);
    }
    for (side, end) in [("left", &f.chain.left), ("right", &f.chain.right)] {
        if matches!(end, Some(EndFile::Wall(_))) {
            return Err(format!(
                "the outer medium ends the chain with free ends beyond its outer chains, but \
                 `chain.{side}` is a wall: remove the wall or the outer medium"
            ));
        }
    }
    let sections = &mut f.chain.sections;
    let find = |name: &str| {
        sections
            .iter()
            .position(|s| s.name.as_deref() == Some(name))
            .ok_or_else(|| {
                format!("an outer medium needs a section named `{name}` (the container contract of scenes/containers/)")
            })
    };
    let (left, right, beyond) = (
        find("outer-left")?,
        find("outer-right")?,
        find("beyond-striker")?,
    );
    if left != 0 || beyond + 1 != sections.len() {
        return Err("an outer medium needs `outer-left` first and `beyond-striker` last".into());
    }
    // On the right, the grains from the container to the striker are the scene's own: the
    // medium's distance must cover them, the striker and at least one grain beyond it.
    let near = sections[right].count;
    let rest = distance
        .checked_sub(near)
        .and_then(|d| d.checked_sub(1))
        .filter(|&d| d >= 1)
        .ok_or_else(|| {
            format!(
                "distance ({distance}) must cover the grains from the container to the striker \
                 (`outer-right`, {near}), the striker and one grain beyond it: at least {} grains",
                near.saturating_add(2)
            )
        })?;
    // Both at most 1e6 (the medium's bound) or a checked count of the file: no wrap.
    let shift = i64::try_from(distance).unwrap_or(i64::MAX)
        - i64::try_from(sections[left].count).unwrap_or(i64::MAX);
    sections[left].count = distance;
    sections[beyond].count = rest;
    let (mass, mut law) = (sections[beyond].mass, sections[beyond].law.clone());
    shift_grains(f, shift);
    f.chain.left = Some(EndFile::Free);
    f.chain.right = Some(EndFile::Free);
    let mut moved = shift;
    if let Some((count, damping, contact_damping)) = layer {
        law.contact_damping = contact_damping;
        let layer = |name: &str| SectionFile {
            name: Some(name.into()),
            count,
            mass,
            diameter: None,
            damping,
            law: law.clone(),
        };
        f.chain.sections.push(layer("layer-right"));
        f.chain.sections.insert(0, layer("layer-left"));
        // `layer` is at most 1e6 (checked above).
        shift_grains(f, count as i64);
        moved += count as i64;
    }
    Ok(moved)
}
