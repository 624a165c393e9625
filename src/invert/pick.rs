//! [`Pick::Exact`]: the known grid's exact render, not the network, picks the camera among
//! the hypotheses the network's search refined (README "Inverse rendering", "The exact
//! renderer picks the camera").

use super::starts::{POLISH_STEP_DEGREES, light_grid, twin};
use super::{InvertOptions, Inverter, Vars, Window};
use crate::error::Result;
use crate::gpu::Gpu;
use crate::graph::Executor;
use crate::nn::rendernet::RenderNet;
use crate::reference::{Image, View};
use crate::voxel::VoxelGrid;

/// What picks the camera among the search's hypotheses once the network has refined them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pick {
    /// The network's own image MSE (the paper's inverse rendering: nothing but the network).
    Network,
    /// The exact renderer's maps of the known grid ([`Inverter::exact_scores`]): the refined
    /// starts (the refinement's and the light polish's), the subdivided views, the best views
    /// of the ranking before subdivision and the opposite-side twins of all of them are drawn
    /// by the ray marcher (normal, albedo, mask), each lit by its best light of the 20-degree
    /// grid; the lowest image MSE wins, and at a camera other than the network's own pick the
    /// light polish runs again. Last, the exact polish (`Inverter::exact_polish`) refines
    /// camera and light on the exact maps themselves, the grid smoothed as the image prefers.
    /// The network proposes and refines, the grid itself arbitrates: a network's render from
    /// the wrong side can explain an image better than its render from the right one (README
    /// "Inverse rendering", "The exact renderer picks the camera").
    Exact,
}

impl Inverter {
    /// [`Pick::Exact`]: of the `refined` hypotheses (the network's best first), the
    /// `unrefined` views and the far-side twins of all, the one whose exact maps explain
    /// `target` best. Another camera than the network's best carries a light chosen for some
    /// other camera, so the light polish runs again there (`search`: the grid's values, the
    /// target's pixels and the window); its result is kept if its exact maps score no worse,
    /// else the pick's camera with the network's best light of the polish grid there. The
    /// exact score of the camera returned is never above the network's best's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn exact_pick(&self, gpu: &Gpu, grid: &VoxelGrid, target: &Image, refined: &[Vars], unrefined: &[Vars], sil: &mut (RenderNet, Executor), search: (&[f32], &[f32], &Window), o: &InvertOptions) -> Result<Vars> {
        let (gv, crop, win) = search;
        let mut all: Vec<Vars> = refined.iter().chain(unrefined).copied().collect();
        all.extend(all.iter().map(|&v| twin(v)).collect::<Vec<_>>());
        let views: Vec<View> = all.iter().map(Vars::view).collect();
        let scene = self.exact_scene(gpu, grid, target, &views[0])?;
        let scores = self.scores_in(gpu, &scene, &views)?;
        let k = (0..all.len()).min_by(|&a, &b| scores[a].total_cmp(&scores[b])).expect("the network's best is a candidate");
        if k == 0 {
            return Ok(all[0]);
        }
        let (again, _, _) = self.polish(gpu, sil, gv, crop, all[k], o, win)?;
        if self.scores_in(gpu, &scene, &[again.view()])?[0] <= scores[k] {
            return Ok(again);
        }
        Ok(self.ranked_lights(gpu, sil, gv, crop, &[all[k]], win, &light_grid(POLISH_STEP_DEGREES))?[0][0].1)
    }
}
