//! The objective measures of formation-transform section 5.1. CONTRACT ONLY.

/// The three measures of section 5.1 (and `I_v`), for one instant or averaged.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Measures {
    /// `I_d`, eq. 17 (bits).
    pub i_d: f64,
    /// `I_v`: as `I_d`, with speed bins for directions (bits).
    pub i_v: f64,
    /// `σ_min_dis`, eq. 24 (m).
    pub sigma_min_dis_m: f64,
    /// `σ_curr_eft`, eq. 26 (m).
    pub sigma_curr_eft_m: f64,
}
