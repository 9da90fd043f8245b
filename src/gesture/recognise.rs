//! Recognition: a captured gesture against the library (gesture-driven sections 5
//! and 7.1). The gesture is validated, normalised and resampled ([`prepare`]), its
//! four features extracted ([`GestureFeatures::of`]), its K nearest library gestures
//! found by eq. 12 with the pruned search ([`Searcher`]), weighted by eq. 18, and its
//! class voted by the weighted neighbours (section 8.2).
//!
//! A [`Recogniser`] is the library made searchable: every library gesture's features
//! and lower-bound envelopes, computed once when the library is loaded.

use super::error::GestureError;
use super::features::GestureFeatures;
use super::knn::{vote, GestureIndex, Neighbour, SearchParams, Searcher};
use super::library::{ClassId, Library, LibraryError};
use super::resample::prepare;
use super::track::GestureTracks;

/// The library with its gestures' features indexed for search.
#[derive(Debug)]
pub struct Recogniser {
    library: Library,
    index: GestureIndex,
    /// What the library was read from (`library.ctgl (shipped)`, a path).
    source: String,
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
        let features = library
            .gestures
            .iter()
            .map(|g| GestureFeatures::of(&g.gesture))
            .collect();
        Ok(Recogniser {
            index: GestureIndex::with_band(features, band),
            library,
            source: source.into(),
        })
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
    /// buffers.
    ///
    /// # Errors
    /// [`RecogniseError::Gesture`] when the gesture cannot be compared,
    /// [`RecogniseError::EmptyLibrary`] with nothing to compare it with.
    pub fn recognise(
        &self,
        tracks: &GestureTracks,
        params: &SearchParams,
        searcher: &mut Searcher,
    ) -> Result<Recognised, RecogniseError> {
        let features = GestureFeatures::of(&prepare(tracks)?);
        self.recognise_features(&features, params, searcher)
    }

    /// [`recognise`](Self::recognise) for features already extracted.
    ///
    /// # Errors
    /// [`RecogniseError::EmptyLibrary`] with nothing to compare with.
    pub fn recognise_features(
        &self,
        features: &GestureFeatures,
        params: &SearchParams,
        searcher: &mut Searcher,
    ) -> Result<Recognised, RecogniseError> {
        let neighbours = searcher.search(&self.index, features, params).to_vec();
        let (class, weight) =
            vote(&neighbours, |e| self.class_of(e)).ok_or(RecogniseError::EmptyLibrary)?;
        Ok(Recognised {
            class,
            weight,
            neighbours,
        })
    }
}

impl PartialEq for Recogniser {
    /// The same library from the same place (the index follows from it).
    fn eq(&self, other: &Recogniser) -> bool {
        self.source == other.source
            && self.index.band() == other.index.band()
            && self.library == other.library
    }
}
