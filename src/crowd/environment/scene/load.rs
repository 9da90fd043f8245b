//! Loading: a scene file read (a regular file, capped while read) and parsed strictly, every problem
//! located in the text, and checkpoint formations checked against the config's.

use super::file::SceneFile;
use super::limits::MAX_SCENE_BYTES;
use super::model::Scene;
use super::problem::{Problem, SceneError, SceneIssue};
use crate::located::{self, Issue, ReadError};
use std::path::Path;

impl Scene {
    /// Reads and validates a scene file (size-capped at [`MAX_SCENE_BYTES`]).
    /// `agent_radius_m` sets the smallest gap between obstacles (one diameter).
    ///
    /// # Errors
    /// [`SceneError::Io`], [`SceneError::TooLarge`] or [`SceneError::Invalid`] with
    /// every problem.
    pub fn load(path: &Path, agent_radius_m: f64) -> Result<Scene, SceneError> {
        let text = located::read_text(path, MAX_SCENE_BYTES).map_err(|e| match e {
            ReadError::TooLarge { path, size, max } => SceneError::TooLarge { path, size, max },
            ReadError::Io { path, source } => SceneError::Io { path, source },
            e => SceneError::Unreadable(e),
        })?;
        Scene::from_str(&text, path, agent_radius_m)
    }

    /// Parses and validates scene text; `path` is used in messages only.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] listing every problem with line, column and field.
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str, path: &Path, agent_radius_m: f64) -> Result<Scene, SceneError> {
        let file: SceneFile =
            located::parse_strict(text).map_err(|i: Issue| SceneError::Invalid {
                path: path.to_path_buf(),
                issues: vec![SceneIssue {
                    field: i.field,
                    line: i.line,
                    column: i.column,
                    problem: Problem::Syntax { message: i.message },
                }],
            })?;
        let scene = Scene::from_file(&file, agent_radius_m).map_err(|problems| {
            let mut issues: Vec<SceneIssue> = problems
                .into_iter()
                .map(|(field, problem)| {
                    let (line, column) = located::locate_field(text, &field).unwrap_or((0, 0));
                    SceneIssue {
                        field,
                        line,
                        column,
                        problem,
                    }
                })
                .collect();
            issues.sort_by_key(|i| (i.line, i.column));
            SceneError::Invalid {
                path: path.to_path_buf(),
                issues,
            }
        });
        let mut scene = scene?;
        for (i, c) in scene.checkpoints.iter_mut().enumerate() {
            c.formation_at = located::locate_field(text, &format!("checkpoints[{i}].formation"))
                .unwrap_or((0, 0));
        }
        Ok(scene)
    }

    /// Checks that every checkpoint names one of the `known` formations (`start` and
    /// the formation library's names, as `FormationLibrary::known_names` lists them);
    /// `path` is the scene file, for messages.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] with a [`Problem::UnknownFormation`] per checkpoint
    /// that names an unknown one, at its `formation` field.
    pub fn check_formations(&self, path: &Path, known: &[&str]) -> Result<(), SceneError> {
        let issues: Vec<SceneIssue> = self
            .checkpoints
            .iter()
            .enumerate()
            .filter(|(_, c)| !known.contains(&c.formation.as_str()))
            .map(|(i, c)| SceneIssue {
                field: format!("checkpoints[{i}].formation"),
                line: c.formation_at.0,
                column: c.formation_at.1,
                problem: Problem::UnknownFormation {
                    name: c.formation.clone(),
                    known: known.join(", "),
                },
            })
            .collect();
        if issues.is_empty() {
            Ok(())
        } else {
            Err(SceneError::Invalid {
                path: path.to_path_buf(),
                issues,
            })
        }
    }
}
