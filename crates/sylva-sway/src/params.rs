//! Material and model constants of the sway model, with their sources.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A sway parameter out of range.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("sway parameter `{field}` = {value} is invalid: expected {expected}")]
pub struct SwayParamError {
    /// Field name.
    pub field: &'static str,
    /// Value found.
    pub value: f32,
    /// Valid range.
    pub expected: &'static str,
}

/// Constants of the damped-angular-spring model (paper §4.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SwayParams {
    /// Young's modulus of green wood E, Pa (> 0). Default 9 GPa (green hardwoods span about
    /// 6–12 GPa; USDA Wood Handbook, table 5-3a, green modulus of elasticity).
    pub youngs_modulus: f32,
    /// Density of green wood ρ_w, kg/m³ (> 0). Default 800 (green hardwoods ≈ 700–1000).
    pub wood_density: f32,
    /// Damping ratio ζ of every joint, structural plus aerodynamic (0 < ζ < 1). Default
    /// 0.08; measured tree sway shows about 3–10 %, more with a dense crown.
    pub damping_ratio: f32,
    /// Drag coefficient of a branch segment (cylinder in cross-flow), C_d. Default 1.0.
    pub wood_drag: f32,
    /// Drag coefficient of leaves per one-sided leaf area, C_d. Default 0.2 (leaves
    /// streamline and reconfigure; broadleaf crowns measure about 0.1–0.4).
    pub leaf_drag: f32,
    /// Speed U_r at which leaves have halved their drag by reconfiguring (folding, rolling
    /// into cones, crowns streamlining), m/s (> 0): the leaf drag is C_d A |u| u / (1 +
    /// |u| / U_r) — quadratic in light wind, linear in strong wind (a Vogel exponent of −1;
    /// leaves and crowns measure −0.2 to −1.2, de Langre 2008, Annu. Rev. Fluid Mech.).
    /// Default 8: crown drag areas falling by about half between 4 and 20 m/s (Rudnicki,
    /// Mitchell & Novak 2004, three conifers in a wind tunnel). Wood does not reconfigure.
    pub leaf_reconfiguration_speed: f32,
    /// Whole-crown drag coefficient at [`CROWN_DRAG_SPEED`] on the tree's still-air
    /// silhouette (≥ 0; 0 turns the calibration off). Summing every twig's and leaf's own drag
    /// ignores that they shelter each other and bend into the flow: the shipped broadleaf
    /// presets came out at 0.9–1.4 on their silhouettes, five times what wind tunnels
    /// measure on whole crowns. A species whose summed drag at that speed exceeds this
    /// coefficient times its silhouette has every element's drag scaled down to it (see
    /// `SwaySpecies::drag_scale`). Default 0.2: crowns of black cottonwood, red alder and
    /// paper birch measured 0.15–0.22 at 20 m/s (Vollsinger, Mitchell, Byrne, Novak &
    /// Rudnicki 2005, Can. J. For. Res. 35, 1238–1249).
    pub crown_drag: f32,
    /// Air density ρ, kg/m³ (eq. 8). Default 1.2.
    pub air_density: f32,
    /// Time over which a joint switched off by the animation LOD blends its rotation to the
    /// rest pose (and back when switched on), s (> 0). Default 0.5.
    pub blend_time: f32,
}

impl Default for SwayParams {
    fn default() -> Self {
        SwayParams {
            youngs_modulus: 9.0e9,
            wood_density: 800.0,
            damping_ratio: 0.08,
            wood_drag: 1.0,
            leaf_drag: 0.2,
            leaf_reconfiguration_speed: 8.0,
            crown_drag: 0.2,
            air_density: 1.2,
            blend_time: 0.5,
        }
    }
}

/// Wind speed of the whole-crown drag calibration ([`SwayParams::crown_drag`]), m/s.
pub const CROWN_DRAG_SPEED: f32 = 20.0;

/// Drag coefficient per one-sided needle area of a conifer: the leaf value 0.2 times the
/// shoot silhouette-to-total-needle-area ratio, about 0.15 (needles on a shoot shade each
/// other; conifer shoots measure roughly 0.1–0.2), so 0.03.
pub const NEEDLE_LEAF_DRAG: f32 = 0.2 * 0.15;

impl SwayParams {
    /// The defaults for a species whose leaves are needles (`needles`) or broad leaves:
    /// needles take [`NEEDLE_LEAF_DRAG`] per unit of their area.
    pub fn for_leaves(needles: bool) -> SwayParams {
        let d = SwayParams::default();
        if needles { SwayParams { leaf_drag: NEEDLE_LEAF_DRAG, ..d } } else { d }
    }

    /// Check every field; the error names it.
    pub fn validate(&self) -> Result<(), SwayParamError> {
        let check = |ok: bool, field, value: f32, expected| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(SwayParamError { field, value, expected })
            }
        };
        check(self.youngs_modulus > 0.0, "youngs_modulus", self.youngs_modulus, "> 0 Pa")?;
        check(self.wood_density > 0.0, "wood_density", self.wood_density, "> 0 kg/m³")?;
        check(
            self.damping_ratio > 0.0 && self.damping_ratio < 1.0,
            "damping_ratio",
            self.damping_ratio,
            "in (0, 1)",
        )?;
        check(self.wood_drag >= 0.0, "wood_drag", self.wood_drag, "≥ 0")?;
        check(self.leaf_drag >= 0.0, "leaf_drag", self.leaf_drag, "≥ 0")?;
        check(
            self.leaf_reconfiguration_speed > 0.0,
            "leaf_reconfiguration_speed",
            self.leaf_reconfiguration_speed,
            "> 0 m/s",
        )?;
        check(self.crown_drag >= 0.0, "crown_drag", self.crown_drag, "≥ 0 (0: off)")?;
        check(self.air_density > 0.0, "air_density", self.air_density, "> 0 kg/m³")?;
        check(self.blend_time > 0.0, "blend_time", self.blend_time, "> 0 s")?;
        Ok(())
    }
}
