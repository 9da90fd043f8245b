//! Motion types: how an agent moves over the ground it stands on.

use serde::{Deserialize, Serialize};

/// Motion types of mesh-formation-control Table 1.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MotionType {
    /// Open ground (the reference motion).
    #[default]
    Run,
    /// Under a low ceiling or net.
    Crawl,
    /// Under branches.
    Duck,
    /// Through water.
    Swim,
    /// Over a low obstacle (single step).
    Jump,
    /// Up a wall (single step).
    ClimbUp,
    /// Down a wall (single step).
    ClimbDown,
}

impl MotionType {
    /// Every motion type, in Table 1 order.
    pub const ALL: [MotionType; 7] = [
        MotionType::Run,
        MotionType::Crawl,
        MotionType::Duck,
        MotionType::Swim,
        MotionType::Jump,
        MotionType::ClimbUp,
        MotionType::ClimbDown,
    ];

    /// The average travel speed relative to running, from motion data.
    ///
    /// # Formula
    /// mesh-formation-control Table 1: run 1.0, crawl 0.33, duck 0.30, swim 0.46,
    /// jump 1.24, climb up 0.50, climb down 0.48.
    ///
    /// # Units
    /// Dimensionless (a factor on the agent's running speed).
    pub fn default_speed_factor(self) -> f64 {
        match self {
            MotionType::Run => 1.0,
            MotionType::Crawl => 0.33,
            MotionType::Duck => 0.30,
            MotionType::Swim => 0.46,
            MotionType::Jump => 1.24,
            MotionType::ClimbUp => 0.50,
            MotionType::ClimbDown => 0.48,
        }
    }

    /// Single-step motions play once per crossing; their patch may be no longer than
    /// the motion's trajectory (mesh-formation-control section 6.2.3).
    pub fn is_single_step(self) -> bool {
        matches!(
            self,
            MotionType::Jump | MotionType::ClimbUp | MotionType::ClimbDown
        )
    }

    /// The name used in files.
    pub fn as_str(self) -> &'static str {
        match self {
            MotionType::Run => "run",
            MotionType::Crawl => "crawl",
            MotionType::Duck => "duck",
            MotionType::Swim => "swim",
            MotionType::Jump => "jump",
            MotionType::ClimbUp => "climb_up",
            MotionType::ClimbDown => "climb_down",
        }
    }
}
