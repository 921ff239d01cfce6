//! `[kernel]` and the `[material.<name>]` tables.

use super::Ctx;
use crate::error::Result;
use peritherm_core::gather::{ColumnIndex, Precision, StepStorage};
use peritherm_core::kernel::{Calibration, Kernel, PartialVolume, Profile};
use peritherm_core::material::{any_phase_change, BondRule, Material};
use peritherm_core::solve::integrator::{Integrator, Stepping};
use peritherm_core::symmetry::Symmetry;
use peritherm_core::weights::Order;
use serde::Deserialize;
use std::collections::BTreeMap;

/// `[kernel]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelSpec {
    /// Exponent p: 1 or 2.
    #[serde(default = "default_p")]
    pub p: u8,
    /// Profile: constant, conical (alias triangular).
    #[serde(default = "default_profile")]
    pub profile: Profile,
    /// Partial volumes: algorithm1 or all_or_nothing.
    #[serde(default = "default_pv")]
    pub partial_volume: PartialVolume,
    /// Bond conductivity between materials: harmonic, lower, arithmetic.
    #[serde(default)]
    pub bond_rule: BondRule,
    /// Normalisation: continuum (exact integral, default) or lattice (midpoint sum).
    #[serde(default)]
    pub calibration: Calibration,
    /// Consistent weights: quadratic (default on meshes), linear, or none (default on boxes).
    #[serde(default)]
    pub consistency: Option<Order>,
    /// Older spelling of `consistency = "linear"`.
    #[serde(default)]
    pub linear_consistency: bool,
    /// Restore the horizon's second moment at nodes whose bonds a pre-crack cuts.
    #[serde(default)]
    pub crack_correction: bool,
    /// The explicit step's column index: u32 (default) or packed (about 1 B per bond).
    #[serde(default)]
    pub columns: ColumnIndex,
    /// The precision of K as the explicit step reads it: f64 (default) or f32.
    #[serde(default)]
    pub precision: Precision,
}

fn default_p() -> u8 {
    2
}
fn default_profile() -> Profile {
    Profile::Constant
}
fn default_pv() -> PartialVolume {
    PartialVolume::Algorithm1
}

impl Default for KernelSpec {
    fn default() -> Self {
        KernelSpec {
            p: default_p(),
            profile: default_profile(),
            partial_volume: default_pv(),
            bond_rule: BondRule::default(),
            calibration: Calibration::default(),
            consistency: None,
            linear_consistency: false,
            crack_correction: false,
            columns: ColumnIndex::default(),
            precision: Precision::default(),
        }
    }
}

impl KernelSpec {
    /// The consistency order asked for, or the default: quadratic on meshes, none on boxes.
    pub(super) fn order(&self, mesh: bool) -> Order {
        match (self.consistency, self.linear_consistency) {
            (Some(o), _) => o,
            (None, true) => Order::Linear,
            (None, false) if mesh => Order::Quadratic,
            (None, false) => Order::None,
        }
    }

    /// Consistent weights are refused on a symmetric body, and asked for by one key only.
    pub(super) fn check_symmetry(&self, cx: Ctx, symmetry: Symmetry) -> Result<()> {
        let asked = self.linear_consistency || self.consistency.is_some_and(|o| o != Order::None);
        if symmetry.is_symmetric() && asked {
            return Err(cx.err(
                if self.linear_consistency {
                    "kernel.linear_consistency"
                } else {
                    "kernel.consistency"
                },
                format!(
                    "does not apply with symmetry = \"{}\": the correction zeroes every node's first moment Σ K_ij ξ_ij, which the ring/shell pair factors must keep (it carries the (1/r)∂θ/∂r term, Bobaru & Duangpanya's axisymmetric form, doi:10.1007/s42102-022-00092-3 eqs 10, 21)",
                    symmetry.name()
                ),
            ));
        }
        let keys = [
            self.linear_consistency.then_some(()),
            self.consistency.map(|_| ()),
        ];
        cx.at_most_one(
            keys,
            (
                "kernel.linear_consistency",
                "give either linear_consistency or consistency, not both",
            ),
        )?;
        Ok(())
    }

    /// How the explicit step reads K. f32 is refused where it would not be used: implicit,
    /// steady and phase-change runs solve with K in f64.
    pub(super) fn step(
        &self,
        cx: Ctx,
        integrator: Integrator,
        materials: &[Material],
    ) -> Result<StepStorage> {
        let phase = any_phase_change(materials);
        let explicit = matches!(integrator.stepping(), Stepping::Explicit(_));
        if self.precision == Precision::F32 && (!explicit || phase) {
            return Err(cx.err(
                "kernel.precision",
                format!(
                    "\"f32\" applies to the explicit step (integrator = \"euler\" or \"rk4\", without phase change); {} solves with K in f64: remove the key or use an explicit integrator",
                    if phase { "a phase-change run" } else { "this integrator" }
                ),
            ));
        }
        Ok(StepStorage {
            columns: self.columns,
            precision: self.precision,
        })
    }

    /// The kernel of the model (`p` is 1 or 2).
    pub(super) fn validate(&self, cx: Ctx) -> Result<Kernel> {
        if self.p != 1 && self.p != 2 {
            return Err(cx.err("kernel.p", format!("must be 1 or 2, got {}", self.p)));
        }
        Ok(Kernel {
            p: self.p,
            profile: self.profile,
            partial_volume: self.partial_volume,
            calibration: self.calibration,
        })
    }
}

/// Validates the `[material.<name>]` tables (at least one), in name order.
pub(super) fn materials(cx: Ctx, given: &BTreeMap<String, Material>) -> Result<Vec<Material>> {
    if given.is_empty() {
        return Err(cx.err("material", "define at least one [material.<name>]"));
    }
    let mut materials = Vec::new();
    for (name, m) in given {
        m.check()
            .map_err(|(key, message)| cx.err(format!("material.{name}.{key}"), message))?;
        materials.push(*m);
    }
    Ok(materials)
}
