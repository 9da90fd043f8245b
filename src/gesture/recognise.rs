//! Recognition: a captured gesture against the library (gesture-driven sections 5
//! and 7.1). The gesture is validated, normalised and resampled ([`prepare_scaled`]),
//! its four features extracted ([`GestureFeatures::of`]) and its physical features
//! ([`PhysicalFeatures::of`], before eq. 2's scaling), its K nearest library gestures
//! found by eq. 12 plus the weighted physical distance with the pruned search
//! ([`Searcher`]), weighted by eq. 18, and its class voted by the weighted neighbours
//! (section 8.2). Then rejection (`reject.rs`): a weak vote, far neighbours or
//! fingers that barely moved give no class.
//!
//! A [`Recogniser`] is the library made searchable: every library gesture's features,
//! physical features and lower-bound envelopes, computed once when the library is
//! loaded. [`Recogniser::baseline`] is the paper's recogniser (eq. 12 alone, nothing
//! rejected), kept to report beside the new one.

use super::error::GestureError;
use super::features::GestureFeatures;
use super::knn::{vote, GestureIndex, Neighbour, SearchParams, Searcher};
use super::library::{ClassId, Library, LibraryError, Resampled};
use super::physical::{PhysicalFeatures, PhysicalWeights};
use super::reject::{Movement, RejectParams, Rejection};
use super::resample::prepare_scaled;
use super::track::GestureTracks;

/// The library with its gestures' features indexed for search.
#[derive(Debug)]
pub struct Recogniser {
    library: Library,
    index: GestureIndex,
    /// What the library was read from (`library.ctgl (shipped)`, a path).
    source: String,
    /// When a recognition is refused.
    reject: RejectParams,
    /// How many times a gesture drawn by a person (a participant id) weighs a
    /// generated one's (1: the same).
    collected_weight: f64,
}

/// A gesture classified: what the vote says and, when the outcome is "none", why.
#[derive(Clone, Debug, PartialEq)]
pub struct Classified {
    /// The vote (the class it would be).
    pub recognised: Recognised,
    /// Why it is not a command, if it is not.
    pub rejection: Option<Rejection>,
}

/// A gesture recognised: its class, how much of the neighbours' weight voted for
/// it, and the neighbours themselves (nearest first).
#[derive(Clone, Debug, PartialEq)]
pub struct Recognised {
    /// The class voted by the weighted neighbours (section 8.2), in the library's
    /// class table ([`Recogniser::class_name`] names it).
    pub class: ClassId,
    /// The summed eq. 18 weight of the neighbours of that class, in `[0, 1]`.
    pub weight: f64,
    /// The K nearest library gestures (entry, eq. 12 distance, eq. 18 weight).
    pub neighbours: Vec<Neighbour>,
}

/// Why a gesture was not recognised.
#[derive(Debug, thiserror::Error)]
pub enum RecogniseError {
    /// The gesture itself cannot be compared (no extent, NaN, ...).
    #[error(transparent)]
    Gesture(#[from] GestureError),
    /// The library holds no gesture.
    #[error("the gesture library is empty")]
    EmptyLibrary,
    /// The gesture is not a command (a weak vote, far neighbours, fingers that
    /// barely moved).
    #[error("{0}")]
    Rejected(Rejection),
}

impl Recogniser {
    /// Indexes `library` (features of every gesture; the band of the index is the
    /// one searches will mostly use, `None` for the paper's unconstrained DTW).
    ///
    /// # Errors
    /// None today beyond what the library's own validation found when it was read;
    /// kept fallible so that a library built in memory is checked the same way.
    pub fn new(
        library: Library,
        source: impl Into<String>,
        band: Option<usize>,
    ) -> Result<Recogniser, LibraryError> {
        Recogniser::with_params(
            library,
            source,
            band,
            PhysicalWeights::default(),
            RejectParams::default(),
        )
    }

    /// The paper's recogniser: eq. 12 alone, nothing rejected.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn baseline(
        library: Library,
        source: impl Into<String>,
        band: Option<usize>,
    ) -> Result<Recogniser, LibraryError> {
        Recogniser::with_params(
            library,
            source,
            band,
            PhysicalWeights::BASELINE,
            RejectParams::NONE,
        )
    }

    /// A recogniser with the given distance weights and rejection thresholds.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_params(
        library: Library,
        source: impl Into<String>,
        band: Option<usize>,
        weights: PhysicalWeights,
        reject: RejectParams,
    ) -> Result<Recogniser, LibraryError> {
        let features = library
            .gestures
            .iter()
            .map(|g| GestureFeatures::of(&g.gesture))
            .collect();
        let physical = library
            .gestures
            .iter()
            .map(|g| PhysicalFeatures::of(&g.gesture, g.scale_mm))
            .collect();
        Ok(Recogniser {
            index: GestureIndex::with_physical(features, physical, weights, band),
            library,
            source: source.into(),
            reject,
            collected_weight: 1.0,
        })
    }

    /// Gestures people drew (a participant id: `library collect`, `library add
    /// --participant`) weigh `w` times a generated one's in the vote and in the
    /// blend (issue 28 item 6: generated gestures are the cold start): each such
    /// neighbour's eq. 18 weight is multiplied by `w` and the weights renormalised
    /// to sum to 1. `w` below 1 or not finite is taken as 1.
    pub fn with_collected_weight(mut self, w: f64) -> Recogniser {
        self.collected_weight = if w.is_finite() { w.max(1.0) } else { 1.0 };
        self
    }

    /// How much more a collected gesture weighs ([`with_collected_weight`](Self::with_collected_weight)).
    pub fn collected_weight(&self) -> f64 {
        self.collected_weight
    }

    /// Applies the collected gestures' weight to `neighbours` (in place, still
    /// summing to 1).
    fn weigh_collected(&self, neighbours: &mut [Neighbour]) {
        if self.collected_weight == 1.0 {
            return;
        }
        let collected = |e: usize| {
            self.library
                .gestures
                .get(e)
                .is_some_and(|g| !g.participant.is_empty())
        };
        if !neighbours.iter().any(|n| collected(n.entry)) {
            return;
        }
        for n in neighbours.iter_mut() {
            if collected(n.entry) {
                n.weight *= self.collected_weight;
            }
        }
        let total: f64 = neighbours.iter().map(|n| n.weight).sum();
        if total > 0.0 && total.is_finite() {
            for n in neighbours.iter_mut() {
                n.weight /= total;
            }
        }
    }

    /// The rejection thresholds.
    pub fn reject_params(&self) -> &RejectParams {
        &self.reject
    }

    /// The library.
    pub fn library(&self) -> &Library {
        &self.library
    }

    /// The features index.
    pub fn index(&self) -> &GestureIndex {
        &self.index
    }

    /// Where the library came from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The class of library gesture `entry` (the first class for an entry out of
    /// range, which the index never gives).
    pub fn class_of(&self, entry: usize) -> ClassId {
        self.library
            .gestures
            .get(entry)
            .map_or(ClassId(0), |g| g.class)
    }

    /// The name of class `id` in the library.
    pub fn class_name(&self, id: ClassId) -> &str {
        self.library.class_name(id)
    }

    /// Recognises `tracks` (mm of glass) with `params`, reusing `searcher`'s
    /// buffers: the class, or why the gesture is not a command.
    ///
    /// # Errors
    /// [`RecogniseError::Gesture`] when the gesture cannot be compared,
    /// [`RecogniseError::EmptyLibrary`] with nothing to compare it with,
    /// [`RecogniseError::Rejected`] when it is not a command.
    pub fn recognise(
        &self,
        tracks: &GestureTracks,
        params: &SearchParams,
        searcher: &mut Searcher,
    ) -> Result<Recognised, RecogniseError> {
        let c = self.classify(tracks, params, searcher)?;
        match c.rejection {
            Some(r) => Err(RecogniseError::Rejected(r)),
            None => Ok(c.recognised),
        }
    }

    /// Classifies `tracks`: the vote, and the rejection if there is one.
    ///
    /// # Errors
    /// [`RecogniseError::Gesture`], [`RecogniseError::EmptyLibrary`].
    pub fn classify(
        &self,
        tracks: &GestureTracks,
        params: &SearchParams,
        searcher: &mut Searcher,
    ) -> Result<Classified, RecogniseError> {
        let (drawn, scale_mm) = prepare_scaled(tracks)?;
        self.classify_prepared(&drawn, scale_mm, &Movement::of(tracks), params, searcher)
    }

    /// [`classify`](Self::classify) for a gesture already resampled (with its eq. 2
    /// scale, mm) and its raw movement.
    ///
    /// # Errors
    /// [`RecogniseError::EmptyLibrary`].
    pub fn classify_prepared(
        &self,
        drawn: &Resampled,
        scale_mm: f64,
        movement: &Movement,
        params: &SearchParams,
        searcher: &mut Searcher,
    ) -> Result<Classified, RecogniseError> {
        let features = GestureFeatures::of(drawn);
        let physical = PhysicalFeatures::of(drawn, Some(scale_mm));
        let mut neighbours = searcher
            .search_with(&self.index, &features, &physical, params)
            .to_vec();
        self.weigh_collected(&mut neighbours);
        let (class, weight) =
            vote(&neighbours, |e| self.class_of(e)).ok_or(RecogniseError::EmptyLibrary)?;
        let r = &self.reject;
        let nearest = neighbours.first().map_or(0.0, |n| n.distance);
        let rejection = movement.check(r).or_else(|| {
            if weight < r.min_vote {
                Some(Rejection::WeakVote {
                    class: self.class_name(class).to_string(),
                    weight,
                    min: r.min_vote,
                })
            } else if nearest > r.max_nearest {
                Some(Rejection::Far {
                    distance: nearest,
                    max: r.max_nearest,
                })
            } else {
                None
            }
        });
        Ok(Classified {
            recognised: Recognised {
                class,
                weight,
                neighbours,
            },
            rejection,
        })
    }
}

impl PartialEq for Recogniser {
    /// The same library from the same place (the index follows from it).
    fn eq(&self, other: &Recogniser) -> bool {
        self.source == other.source
            && self.index.band() == other.index.band()
            && self.index.physical_weights() == other.index.physical_weights()
            && self.reject == other.reject
            && self.collected_weight == other.collected_weight
            && self.library == other.library
    }
}
