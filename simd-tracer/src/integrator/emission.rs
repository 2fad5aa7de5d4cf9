//! Deferred emission products: `Σ w T` per emission spectrum, one product
//! with `Le` per path (the truncated product is bilinear).

use super::EMISSION_SLOTS;
use crate::ids::SpectrumId;
use crate::scene::Scene;
use crate::simd::{LANES, LaneMask};
use crate::transport::Transport;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// One emission term per lane: the spectrum `through` which the emission
/// reaches the camera (a throughput, or a throughput times a BSDF), the
/// emission spectrum of each lane, the lanes that see it and their scalar
/// weights (MIS, or 1).
#[derive(Debug, Clone, Copy)]
pub(super) struct Emitted<'a, S> {
    pub(super) through: &'a S,
    pub(super) emission: &'a [SpectrumId; LANES],
    pub(super) lanes: LaneMask,
    pub(super) weight: f32x8,
}

/// Deferred emission products. Every emitted contribution has the form
/// `T ⊛ Le · w` with a per-lane scalar `w`; the truncated product is
/// bilinear, so `Σ_k T_k ⊛ Le · w_k = (Σ_k w_k T_k) ⊛ Le`. Sums are kept per
/// emission spectrum (up to [`EMISSION_SLOTS`], then products are formed
/// directly) and multiplied by their spectrum once per path: one truncated
/// product per bounce (the BSDF factor) instead of three.
pub(super) struct EmissionSums<S> {
    pub(super) ids: [Option<SpectrumId>; EMISSION_SLOTS],
    pub(super) sums: [S; EMISSION_SLOTS],
    pub(super) direct: S,
}

impl<S: Copy> EmissionSums<S> {
    pub(super) fn new<T: Transport<Spectra = S>>(transport: &T) -> Self {
        Self {
            ids: [None; EMISSION_SLOTS],
            sums: [transport.zero(); EMISSION_SLOTS],
            direct: transport.zero(),
        }
    }

    /// Empties the sums for a new path: the slots are released (a slot's
    /// sum is set when it is claimed), the direct sum is zeroed.
    pub(super) fn reset<T: Transport<Spectra = S>>(&mut self, transport: &T) {
        self.ids = [None; EMISSION_SLOTS];
        self.direct = transport.zero();
    }

    /// Adds `through ⊛ Le(emission[lane]) · weight(lane)` for each lane of
    /// `lanes` ([`Emitted`]).
    pub(super) fn add<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        emitted: &Emitted<'_, S>,
    ) {
        let Emitted {
            through: value,
            emission: ids,
            lanes,
            weight,
        } = *emitted;
        let Some(first) = lanes.iter().next() else {
            return;
        };
        let live = lanes.to_simd();
        let weight = live.select(weight, f32x8::ZERO);
        // Lanes whose weight is not 0 (a NaN weight counts).
        let weighted = !weight.simd_eq(f32x8::ZERO);
        // The common case, one emission among the lanes: one scaled sum,
        // the same as the loop below forms for it.
        let id = ids[first];
        let same: f32x8 = cast(u32x8::new(SpectrumId::words(*ids)).simd_eq(u32x8::splat(id.0)));
        if (same | !live).all() {
            if weighted.any() {
                self.add_scaled(transport, scene, wavelengths, value, id, weight);
            }
            return;
        }
        let mut done = LaneMask::NONE;
        let weighted = LaneMask::from_simd(weighted);
        for lane in lanes.and(weighted).iter() {
            if done.contains(lane) {
                continue;
            }
            let id = ids[lane];
            let of_id: f32x8 =
                cast(u32x8::new(SpectrumId::words(*ids)).simd_eq(u32x8::splat(id.0)));
            let of_id = LaneMask::from_simd(of_id).and(lanes);
            done = done.or(of_id);
            let lane_weights = of_id.to_simd().select(weight, f32x8::ZERO);
            self.add_scaled(transport, scene, wavelengths, value, id, lane_weights);
        }
    }

    /// Adds `value ⊛ Le(id) · weight(lane)` (to the slot of `id` if there
    /// is one, else directly).
    #[inline(always)]
    pub(super) fn add_scaled<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        value: &S,
        id: SpectrumId,
        lane_weights: f32x8,
    ) {
        let scaled = transport.scale(value, lane_weights);
        let slot = match self.ids.iter().position(|&s| s == Some(id)) {
            Some(slot) => Some(slot),
            None => self.ids.iter().position(Option::is_none).inspect(|&slot| {
                // A claimed slot starts from zero.
                self.ids[slot] = Some(id);
                self.sums[slot] = transport.zero();
            }),
        };
        match slot {
            Some(slot) => self.sums[slot] = transport.add(&self.sums[slot], &scaled),
            None => {
                let le = transport.gather_ids(scene, wavelengths, &[id; LANES], LaneMask::ALL);
                self.direct = transport.add(&self.direct, &transport.mul(&scaled, &le));
            }
        }
    }

    /// Adds `value ⊛ le · weight(lane)` directly (emission that is not a
    /// scene spectrum, such as an environment map's texels).
    pub(super) fn add_direct<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        value: &S,
        le: &S,
        weight: f32x8,
    ) {
        let scaled = transport.scale(value, weight);
        self.direct = transport.add(&self.direct, &transport.mul(&scaled, le));
    }

    /// The radiance summed so far in the lanes of `lanes` (0 elsewhere),
    /// which start again from zero (a fluorescent event closes what its
    /// lanes gathered on the camera side of it).
    pub(super) fn take<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        lanes: LaneMask,
    ) -> S {
        let zero = transport.zero();
        let taken = transport.select(lanes, &self.finish(transport, scene, wavelengths), &zero);
        for (id, sum) in self.ids.iter().zip(&mut self.sums) {
            if id.is_some() {
                *sum = transport.select(lanes, &zero, sum);
            }
        }
        self.direct = transport.select(lanes, &zero, &self.direct);
        taken
    }

    /// The total radiance.
    pub(super) fn finish<T: Transport<Spectra = S>>(
        &self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
    ) -> S {
        let mut radiance = self.direct;
        for (id, sum) in self.ids.iter().zip(&self.sums) {
            if let Some(id) = *id {
                let le = transport.gather_ids(scene, wavelengths, &[id; LANES], LaneMask::ALL);
                radiance = transport.add(&radiance, &transport.mul(sum, &le));
            }
        }
        radiance
    }
}
