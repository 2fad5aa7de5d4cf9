//! The camera side of light-traced caustics (`render/light_paths.rs`):
//! which of a packet's paths belong to the light paths' share of path
//! space, so that the camera paths leave them out.
//!
//! A path `x₁ … x_k` from the camera to an emissive triangle is the light
//! paths' when
//!
//! * its first surface `x₁` scattered through a non-delta lobe (a light
//!   path reaches the camera by a connection from such a vertex), and
//! * the events between its last non-delta vertex and the emitter are all
//!   delta, at least one of them on a material that disperses (a
//!   refraction through dispersive glass, whose direction depends on
//!   wavelength, or a reflection off its surface: light that a shadow ray
//!   cannot follow, which a camera path finds only by chance), and
//! * the emitter is one the light paths start from: a triangle of the
//!   light set or of a sphere light (instances and the environment are
//!   not; point and spot lights, which light paths start from too, no
//!   camera path reaches).
//!
//! Every other path stays the camera paths'. Both sides classify a vertex
//! the same way — by the lobe that scattered there (a light sample or
//! connection is a non-delta event; a sampled lobe with pdf 0 a delta
//! one) and by its material ([`crate::shading::material::Bsdf::disperses`])
//! — so the two sets partition path space: each path is counted by
//! exactly one estimator, and the sum is unbiased without weights.
//!
//! **Why reflections too.** The glass's surface mirrors about a tenth of a
//! lamp's light (SF11 at normal incidence: `((n − 1)/(n + 1))² ≈ 0.08`);
//! left to the camera paths, the light it mirrors onto a wall or a sphere
//! was found only by the few paths whose bounce happens to reflect onto
//! the lamp, as bright isolated pixels in `prism` (measured in
//! `docs/results.md`, "Reflections off the glass to the light paths").
//! The light paths are aimed at the dispersive glass anyway, and a
//! reflected one lands where it belongs.

use crate::simd::LaneMask;

/// The partition's state of a packet's paths (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CausticLanes {
    /// Lanes whose first surface scattered through a non-delta lobe.
    scattered_first: LaneMask,
    /// Lanes whose events since their last non-delta one are all delta,
    /// at least one of them on a material that disperses.
    dispersive_chain: LaneMask,
}

impl CausticLanes {
    /// No path yet.
    pub const NONE: Self = Self {
        scattered_first: LaneMask::NONE,
        dispersive_chain: LaneMask::NONE,
    };

    /// Records the events that the bounce at `depth` sampled for its lanes
    /// `active`: `delta` took a delta lobe, and of those `dispersive_delta`
    /// did so on a material that disperses.
    pub(super) fn after_sample(
        &mut self,
        depth: u32,
        active: LaneMask,
        delta: LaneMask,
        dispersive_delta: LaneMask,
    ) {
        let delta = delta.and(active);
        if depth == 1 {
            self.scattered_first = active.and_not(delta);
        }
        let chain = self.dispersive_chain.or(dispersive_delta);
        self.dispersive_chain = chain.and(delta);
    }

    /// Where a child (`ChildPath`) of lane `lane` starts, whose own sample
    /// of the surface that spawned it was `delta`, on a material that
    /// disperses where `dispersive`: `self` is the parent's state before
    /// that event (the child's event replaces the hero's). Returns the
    /// child's `(scattered_first, dispersive_chain)`.
    pub(super) fn child(
        &self,
        lane: usize,
        depth: u32,
        delta: bool,
        dispersive: bool,
    ) -> (bool, bool) {
        let scattered_first = if depth == 1 {
            !delta
        } else {
            self.scattered_first.contains(lane)
        };
        let chain = (self.dispersive_chain.contains(lane) || dispersive) && delta;
        (scattered_first, chain)
    }

    /// The state of a packet of children: the lanes `scattered_first` and
    /// `dispersive_chain` of their [`crate::integrator::ChildPath`]s.
    pub fn of_children(scattered_first: LaneMask, dispersive_chain: LaneMask) -> Self {
        Self {
            scattered_first,
            dispersive_chain,
        }
    }

    /// Of the lanes `emitters` (hits on triangles that light paths start
    /// from, by a BSDF-sampled ray), those whose paths the light paths
    /// carry.
    pub(super) fn light_traced(&self, emitters: LaneMask) -> LaneMask {
        emitters
            .and(self.scattered_first)
            .and(self.dispersive_chain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Paths diffuse → glass → glass → lamp are the light paths'; a path
    /// whose first event is delta, a chain without dispersion, or a chain
    /// broken by a non-delta event is not.
    #[test]
    fn chains_of_dispersive_delta_events_after_a_first_diffuse_one() {
        let all = LaneMask(0b1111);
        let mut lanes = CausticLanes::NONE;
        // Lane 0: diffuse first; lane 1: delta (mirror) first; lanes 2, 3 diffuse.
        lanes.after_sample(1, all, LaneMask(0b0010), LaneMask::NONE);
        // Depth 2: lanes 0, 1, 2 refract through dispersive glass, lane 3 a mirror.
        lanes.after_sample(2, all, LaneMask(0b1111), LaneMask(0b0111));
        // Depth 3: lane 2 scatters diffusely again, the others leave the glass.
        lanes.after_sample(
            3,
            all,
            LaneMask(0b1011),
            LaneMask(0b1011).and(LaneMask(0b0011)),
        );
        assert_eq!(lanes.light_traced(all), LaneMask(0b0001));
        assert_eq!(lanes.light_traced(LaneMask(0b1110)), LaneMask::NONE);
        // A mirror after the glass keeps the chain.
        lanes.after_sample(4, all, LaneMask(0b0001), LaneMask::NONE);
        assert_eq!(lanes.light_traced(all), LaneMask(0b0001));
    }
}
