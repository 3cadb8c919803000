//! The default design space of `case init` ([`default_space`]), built part by part
//! ([`super::parts`]):
//!
//! * a **wing** gets the wing master of §6 when one of its surfaces is wrapped round the
//!   leading edge ([`super::wing`]: `wing.sweep`, `wing.dihedral`, `wing.twist.root`,
//!   `wing.twist.tip`, `wing.chord.tip`, `wing.tmax.root`, `wing.tmax.tip`,
//!   `wing.camber.tip`);
//! * a **fuselage** gets the waist at the wing junction of Fig. 9 ([`super::fuselage`]:
//!   `fuselage.waist`), the nose droop of Fig. 10 and the stretch of Fig. 12 ahead of the
//!   junction ([`super::nose`]: `fuselage.droop`, `fuselage.stretch`);
//! * any other part, and a wing or fuselage for which the above cannot be built (the reason
//!   is noted), gets one smooth bump along the normal per support surface (surface level,
//!   Eq. 38, the middle Bernstein function of degree 2 in u and in v: zero on the border of
//!   the surface's parameter domain, largest at its centre), named after the component
//!   (`body.D123.bump`).
//!
//! Then every variable that moves no control node is left out ([`drop_dead`]), with a note.

use std::collections::BTreeMap;

use geom_db::{GeomDb, SurfaceId};
use param::{
    Basis, DesignVariable, Direction, Modifier, Parametrisation, SurfaceForm, SurfaceModifier,
};
use wingmaster::WingMasterSpec;

use super::parts::{Kind, parts, shared_curves};
use super::{fuselage, nose, wing};

/// A design space: the parametrisation, the wing masters its master modifiers use, what was
/// built and what was left out.
#[derive(Debug, Clone, Default)]
pub struct Space {
    /// The modifiers and their variables.
    pub parametrisation: Parametrisation,
    /// The wing masters, by the name of their `External` source.
    pub wing_masters: BTreeMap<String, WingMasterSpec>,
    /// What each part got, in words.
    pub built: Vec<String>,
    /// What was left out, and why.
    pub notes: Vec<String>,
}

/// A readable name of a surface component for variable names: its name (the import's
/// `role.entity`), else `component k`.
fn component_name(db: &GeomDb, k: usize) -> String {
    let n = db.surface_components[k].name.replace(' ', "_");
    if n.is_empty() {
        format!("component{k}")
    } else {
        n
    }
}

/// The distinct support surfaces of components `comps`.
fn surfaces_of(db: &GeomDb, comps: &[usize]) -> Vec<SurfaceId> {
    let mut s: Vec<SurfaceId> = comps
        .iter()
        .map(|&k| db.surface_components[k].surface)
        .collect();
    s.sort_unstable();
    s.dedup();
    s
}

/// One bump on the support surface of each of the components `comps` (the first component
/// of a surface names it; surfaces in `seen` are skipped and added), with the bound `bound`.
fn bumps(db: &GeomDb, comps: &[usize], bound: f64, seen: &mut Vec<SurfaceId>) -> Vec<Modifier> {
    let mut out = Vec::new();
    for &k in comps {
        let surface = db.surface_components[k].surface;
        if seen.contains(&surface) {
            continue;
        }
        seen.push(surface);
        let name = component_name(db, k);
        out.push(Modifier::Surface(SurfaceModifier {
            name: format!("{name}.bump"),
            surfaces: vec![surface],
            range_u: None,
            range_v: None,
            basis_u: Basis::Bernstein { degree: 2 },
            basis_v: Basis::Bernstein { degree: 2 },
            active_u: Some(vec![1]),
            active_v: Some(vec![1]),
            direction: Direction::Normal,
            form: SurfaceForm::Tensor {
                variables: vec![
                    DesignVariable::new(format!("{name}.bump"), -bound, bound)
                        .with_group(name)
                        .with_scale(bound / 10.0),
                ],
            },
        }));
    }
    out
}

/// The default design space on the wall components `walls` (indices); `bump_bound` is the
/// first bound of a bump (length units).
pub fn default_space(db: &GeomDb, walls: &[usize], bump_bound: f64) -> Space {
    let parts = parts(db, walls);
    let wing_comps: Vec<usize> = parts
        .iter()
        .filter(|p| p.kind == Kind::Wing)
        .flat_map(|p| p.comps.iter().chain(&p.caps).copied())
        .collect();
    let mut space = Space::default();
    let mut seen: Vec<SurfaceId> = Vec::new();
    for part in &parts {
        let mods = &mut space.parametrisation.modifiers;
        let fallback = match part.kind {
            Kind::Wing => {
                let caps: Vec<SurfaceId> = surfaces_of(db, &part.caps);
                match wing::propose(db, &part.role, &surfaces_of(db, &part.comps), &caps) {
                    Ok(p) => {
                        seen.extend(p.modifier.links.surfaces.iter().copied());
                        space.built.push(p.summary);
                        space.wing_masters.insert(part.role.clone(), p.spec);
                        mods.push(Modifier::Master(p.modifier));
                        None
                    }
                    Err(why) => Some(why),
                }
            }
            Kind::Fuselage => {
                let junction = shared_curves(db, &part.comps, &wing_comps);
                let mut whys = Vec::new();
                let mut built = false;
                match fuselage::waist(db, &part.role, &part.comps, &junction) {
                    Ok((m, summary)) => {
                        seen.extend(m.surfaces.iter().copied());
                        space.built.push(summary);
                        mods.push(Modifier::Surface(m));
                        built = true;
                    }
                    Err(why) => whys.push(why),
                }
                let nose = nose::nose(
                    db,
                    &part.role,
                    &part.comps,
                    &part.caps,
                    &junction,
                    &wing_comps,
                );
                match nose {
                    Ok((m, summary)) => {
                        for l in &m {
                            if let Modifier::Line(l) = l {
                                seen.extend(l.links.surfaces.iter().copied());
                            }
                        }
                        space.built.push(summary);
                        mods.extend(m);
                        built = true;
                    }
                    Err(why) => whys.push(why),
                }
                if built {
                    space.notes.extend(whys);
                    None
                } else {
                    Some(whys.join("; "))
                }
            }
            Kind::Other => {
                space.built.push(format!(
                    "{}: one normal bump per surface (neither a wing nor a fuselage)",
                    part.role
                ));
                mods.extend(bumps(db, &part.comps, bump_bound, &mut seen));
                continue;
            }
        };
        if let Some(why) = fallback {
            space.built.push(format!(
                "{}: one normal bump per surface (see the note)",
                part.role
            ));
            space
                .notes
                .push(format!("{why}; one normal bump per surface instead"));
            mods.extend(bumps(db, &part.comps, bump_bound, &mut seen));
        }
    }
    space
}

/// Removes from `space` every design variable that moves no control node, and every
/// modifier that cannot be bound or moves nothing, each with a note naming it.
pub fn drop_dead(db: &GeomDb, space: &mut Space) {
    let modifiers = std::mem::take(&mut space.parametrisation.modifiers);
    for mut m in modifiers {
        let reach = bind_alone(db, &m, &space.wing_masters)
            .and_then(|p| crate::reach::variable_reach(&p).map_err(|e| e.to_string()));
        let reach = match reach {
            Ok(r) => r,
            Err(e) => {
                space.notes.push(format!("{}: left out: {e}", m.name()));
                drop_master(space, &m);
                continue;
            }
        };
        let dead: Vec<String> = reach
            .iter()
            .filter(|r| r.nodes_moved == 0)
            .map(|r| r.name.clone())
            .collect();
        if dead.len() == reach.len() {
            space
                .notes
                .push(format!("{}: left out, it moves no control node", m.name()));
            drop_master(space, &m);
            continue;
        }
        for d in &dead {
            space
                .notes
                .push(format!("{d}: left out, it moves no control node"));
        }
        if !dead.is_empty() {
            remove_variables(&mut m, &dead, &mut space.wing_masters);
        }
        space.parametrisation.modifiers.push(m);
    }
}

/// Removes the design variables `names` from `space`: from a master modifier (and its wing
/// master) one by one, the modifier with them when none is left; any other modifier that
/// holds one of them whole (its variables share one basis).
pub fn leave_out(space: &mut Space, names: &[String]) {
    if names.is_empty() {
        return;
    }
    let modifiers = std::mem::take(&mut space.parametrisation.modifiers);
    for mut m in modifiers {
        let hit = variables_mut(&mut m)
            .iter()
            .any(|v| names.contains(&v.name));
        if !hit {
            space.parametrisation.modifiers.push(m);
            continue;
        }
        if matches!(m, Modifier::Master(_)) {
            remove_variables(&mut m, names, &mut space.wing_masters);
            if !variables_mut(&mut m).is_empty() {
                space.parametrisation.modifiers.push(m);
                continue;
            }
        }
        drop_master(space, &m);
    }
}

/// `m` bound alone (with its wing master, if any).
fn bind_alone(
    db: &GeomDb,
    m: &Modifier,
    masters: &BTreeMap<String, WingMasterSpec>,
) -> Result<param::Prepared, String> {
    let one = Parametrisation {
        modifiers: vec![m.clone()],
        constraints: Vec::new(),
    };
    let sources =
        wingmaster::master::master_sources(db, &one, masters).map_err(|e| e.to_string())?;
    one.bind(db, &sources).map_err(|e| e.to_string())
}

/// Forgets the wing master of a master modifier that was left out.
fn drop_master(space: &mut Space, m: &Modifier) {
    if let Modifier::Master(mm) = m
        && let param::MasterSpec::External(name) = &mm.source
    {
        space.wing_masters.remove(name);
    }
}

/// Removes the variables `names` from `m` (and from its wing master's spec); only master
/// modifiers can hold a dead variable beside live ones here (the others have one).
fn remove_variables(
    m: &mut Modifier,
    names: &[String],
    masters: &mut BTreeMap<String, WingMasterSpec>,
) {
    let Modifier::Master(mm) = m else {
        return;
    };
    mm.variables.retain(|v| !names.contains(&v.name));
    let param::MasterSpec::External(source) = &mm.source else {
        return;
    };
    let Some(spec) = masters.get_mut(source) else {
        return;
    };
    let clear = |o: &mut Option<String>| {
        if o.as_ref().is_some_and(|n| names.contains(n)) {
            *o = None;
        }
    };
    clear(&mut spec.planform.sweep);
    clear(&mut spec.planform.dihedral);
    clear(&mut spec.planform.span);
    for k in &mut spec.key_sections {
        clear(&mut k.twist);
        clear(&mut k.chord);
        k.shift.iter_mut().for_each(clear);
        k.thickness.retain(|_, v| !names.contains(v));
        k.camber.retain(|_, v| !names.contains(v));
    }
}

/// Every design variable of `m`, to be changed in place.
pub fn variables_mut(m: &mut Modifier) -> Vec<&mut DesignVariable> {
    match m {
        Modifier::Node(n) => n
            .rotation
            .iter_mut()
            .chain(n.translation.iter_mut().flatten())
            .collect(),
        Modifier::Line(l) => l.variables.iter_mut().collect(),
        Modifier::Surface(s) => match &mut s.form {
            SurfaceForm::Separable {
                variables_u,
                variables_v,
            } => variables_u.iter_mut().chain(variables_v).collect(),
            SurfaceForm::Tensor { variables } => variables.iter_mut().collect(),
        },
        Modifier::Master(mm) => mm.variables.iter_mut().collect(),
    }
}
