//! The ladder's models ([`LevelBuilds`]): the coarsest model with its inputs' derivatives,
//! the finer levels, and the coarsest mesh with two elements per layer through the thickness
//! (the band's source 'through the thickness'), each from the cache or built and cached (key:
//! the plan (a Gmsh plan's every node), mesh, modes, basis moduli, layers, supports and G_ref).
//!
//! The ladder always needs two finer levels and on a glass laminate usually a third: they are
//! built ahead, on speculation, beside the coarsest ([`LevelBuilds::build_ahead`]: two lanes,
//! the largest level alone on one, the two-element model after it on the lane that frees
//! first). Each build is sequential inside, so the bits do not depend on the schedule. The
//! ladder ([`lamdyn_layered::convergence::converge_keeping_levels`]) takes a level built ahead
//! where there is one and builds the others when it reaches them.

use super::setup::LayeredSetup;
use crate::cache::{Cache, Key};
use crate::text;
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::{Levels, build_level, level_mesh};
use lamdyn_layered::inverse::{BASIS_RATIOS, LayeredInverse, LayeredPlate};
use lamdyn_layered::sensitivity::Input;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Elements per layer through the thickness of the model that checks the ladder's one
/// (the band's source [`crate::band::BandSource::ThroughThickness`]).
pub const THROUGH: usize = 2;

/// A level built ahead: its elements and its model, or why the build failed.
type Built = ([usize; 2], Result<LayeredInverse, LayeredError>);

/// The ladder's models of one run: built ahead, or on demand, through the cache.
pub struct LevelBuilds<'a> {
    setup: &'a LayeredSetup,
    cache: &'a Cache,
    g_ref: f64,
    /// Levels built ahead that the ladder has not taken yet.
    ahead: Mutex<Vec<Built>>,
    /// Whether every model so far came from the cache.
    all_cached: AtomicBool,
}

/// What [`LevelBuilds::build_ahead`] leaves beside the levels it keeps for the ladder.
pub struct BuiltAhead {
    /// The coarsest model, with its inputs' derivatives.
    pub coarsest: LayeredInverse,
    /// The coarsest mesh with [`THROUGH`] elements per layer, or why there is none.
    pub through_thickness: Result<LayeredInverse, NoThroughThickness>,
}

/// Why there is no coarsest mesh with [`THROUGH`] elements per layer (the band then lacks the
/// source 'through the thickness').
#[derive(Debug, Clone, PartialEq)]
pub enum NoThroughThickness {
    /// Its dofs are above `inverse.layered_max_dofs`.
    AboveCap {
        /// Its dofs.
        dofs: usize,
    },
    /// It cannot be meshed.
    NotMeshed(LayeredError),
    /// Its build failed.
    NotBuilt(LayeredError),
}

impl std::fmt::Display for NoThroughThickness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&match self {
            Self::AboveCap { dofs } => text::through_thickness_above_cap(THROUGH, *dofs),
            Self::NotMeshed(e) => text::through_thickness_not_meshed(THROUGH, e),
            Self::NotBuilt(e) => text::through_thickness_not_built(THROUGH, e),
        })
    }
}

impl<'a> LevelBuilds<'a> {
    /// The builds of `setup`'s ladder with basis modulus `g_ref`.
    pub fn new(setup: &'a LayeredSetup, cache: &'a Cache, g_ref: f64) -> Self {
        Self {
            setup,
            cache,
            g_ref,
            ahead: Mutex::new(Vec::new()),
            all_cached: AtomicBool::new(true),
        }
    }

    /// The levels built ahead: the first three finer ones the ladder may reach, up to the dof
    /// cap (the ladder stops below a level above it and says so).
    pub fn levels_ahead(&self) -> Vec<[usize; 2]> {
        let s = &self.setup.ladder;
        (1..=3)
            .filter(|&k| k < s.max_levels)
            .map(|k| level_mesh(self.setup.start, s.ratio, k))
            .take_while(|&m| self.setup.plate.dofs(m).is_ok_and(|d| d <= s.max_dofs))
            .collect()
    }

    /// Builds the coarsest model, the levels `ahead` and the two-element model on two lanes
    /// (module docs); the levels are kept for the ladder.
    ///
    /// # Errors
    /// The coarsest model's build.
    pub fn build_ahead(&self, ahead: &[[usize; 2]]) -> Result<BuiltAhead, LayeredError> {
        let (rest, largest) = ahead.split_at(ahead.len().saturating_sub(1));
        let ((largest, through_thickness), (coarsest, mut built)) = rayon::join(
            || {
                let built: Vec<_> = largest.iter().map(|&m| (m, self.finer(m))).collect();
                (built, self.through_thickness())
            },
            || {
                let coarsest = self.coarsest();
                let rest: Vec<_> = rest.iter().map(|&m| (m, self.finer(m))).collect();
                (coarsest, rest)
            },
        );
        built.extend(largest);
        let coarsest = coarsest?;
        if let Ok(mut a) = self.ahead.lock() {
            *a = built;
        }
        Ok(BuiltAhead {
            coarsest,
            through_thickness,
        })
    }

    /// Whether every model so far came from the cache.
    pub fn all_cached(&self) -> bool {
        self.all_cached.load(Ordering::Relaxed)
    }

    /// The coarsest model, with its inputs' derivatives (from the cache where it is there).
    pub fn coarsest(&self) -> Result<LayeredInverse, LayeredError> {
        self.cached(&self.setup.plate, self.setup.start, true)
    }

    /// A finer level's model on `elements`.
    fn finer(&self, elements: [usize; 2]) -> Result<LayeredInverse, LayeredError> {
        self.cached(&self.setup.plate, elements, false)
    }

    /// The coarsest mesh with [`THROUGH`] elements per layer, or why there is none.
    fn through_thickness(&self) -> Result<LayeredInverse, NoThroughThickness> {
        let two = LayeredPlate {
            elements_per_layer: THROUGH,
            ..self.setup.plate.clone()
        };
        match two.dofs(self.setup.start) {
            Ok(dofs) if dofs > self.setup.ladder.max_dofs => {
                return Err(NoThroughThickness::AboveCap { dofs });
            }
            Err(e) => return Err(NoThroughThickness::NotMeshed(e)),
            Ok(_) => {}
        }
        self.cached(&two, self.setup.start, false)
            .map_err(NoThroughThickness::NotBuilt)
    }

    /// One level's model of `plate` from the cache, else built and cached; `coarsest`: the
    /// coarsest level's (three-modulus basis with the inputs' derivatives), else a finer
    /// level's.
    fn cached(
        &self,
        plate: &LayeredPlate,
        elements: [usize; 2],
        coarsest: bool,
    ) -> Result<LayeredInverse, LayeredError> {
        let modes = if coarsest {
            self.setup.modes
        } else {
            self.setup.ladder.modes
        };
        let mut key = Key::new(concat!(
            "layered basis v7 ",
            env!("CARGO_PKG_VERSION"),
            " ",
            env!("LAMDYN_SOURCE_HASH")
        ))
        .f64(self.g_ref)
        .bytes(
            format!(
                "{:?} {elements:?} {modes} {coarsest} {:?} {}",
                plate.plan, plate.supports, plate.elements_per_layer
            )
            .as_bytes(),
        );
        for l in &plate.layers {
            key = key.bytes(format!("{l:?}").as_bytes());
        }
        if let Some(m) = self
            .cache
            .get("layered", key)
            .and_then(|b| LayeredInverse::from_bytes(&b))
        {
            return Ok(m);
        }
        self.all_cached.store(false, Ordering::Relaxed);
        let m = if coarsest {
            LayeredInverse::build_with_inputs(
                plate,
                elements,
                self.g_ref,
                modes,
                &BASIS_RATIOS,
                &Input::ALL,
            )?
        } else {
            build_level(plate, elements, self.g_ref, modes)?
        };
        self.cache
            .put("layered", key, &m.to_bytes())
            .map_err(|e| LayeredError::Invalid(format!("{e:#}")))?;
        Ok(m)
    }
}

impl Levels for LevelBuilds<'_> {
    fn build(&self, elements: [usize; 2]) -> Result<LayeredInverse, LayeredError> {
        let ready = self.ahead.lock().ok().and_then(|mut a| {
            let i = a.iter().position(|b| b.0 == elements)?;
            Some(a.swap_remove(i).1)
        });
        ready.unwrap_or_else(|| self.finer(elements))
    }

    fn dofs(&self, elements: [usize; 2]) -> Option<usize> {
        self.setup.plate.dofs(elements).ok()
    }
}
