//! The ground of the pictures: the site's window, the terrain around it, streams, wetness and the
//! fade into the sky.

use super::*;

/// The ground of the pictures: the site's window and around it the terrain beyond the window
/// (from the DEM where there is one, else a flat apron), at most 10 m between samples, with
/// what land cover needs per sample (streams, wetness) and the fade of the surroundings into
/// the sky. [`Landscape::mesh`] colours it by the canopy cover of a frame's trees.
#[derive(Debug, Clone, PartialEq)]
pub struct Landscape {
    /// The samples.
    pub ground: crate::render::terrain::GroundGrid,
    /// Land-cover colours (sea level).
    pub cover: LandCover,
    /// Whether the window's trees are mirrored into the surroundings ([`Landscape::surroundings`]);
    /// off for a scenario whose plantings or harvests draw a design on the window
    /// ([`crate::sim::Scenario::designs_its_stand`]), whose mirror images would stand as
    /// phantom parcels on the neighbours' land (trial 40). The ground is drawn either way.
    pub mirror_trees: bool,
}

/// Width (m) over which the edge of the DEM (or of a site without surroundings) fades out.
pub const EDGE_FADE_M: f64 = 150.0;

/// A fractional cell coordinate `v` (cell centres at 0, 1, …, `n` − 1; the grid spans −0.5 to
/// `n` − 0.5) brought into the grid by mirroring it at the grid's ends, as often as needed
/// (period 2`n`): −0.5 − d ↦ −0.5 + d and `n` − 0.5 + d ↦ `n` − 0.5 − d. Inside the grid
/// `v` is returned as it is. The ground beyond a DEM is drawn as its mirror image, which
/// continues the relief across the edge without a seam (the window's trees are mirrored the
/// same way, [`Landscape::surroundings`]); NaN stays NaN. `n` ≥ 1.
pub(super) fn mirrored(v: f64, n: usize) -> f64 {
    let span = n.max(1) as f64;
    if (-0.5..=span - 0.5).contains(&v) || !v.is_finite() {
        return v;
    }
    let t = (v + 0.5).rem_euclid(2.0 * span);
    (if t <= span { t } else { 2.0 * span - t }) - 0.5
}

/// Multi-source breadth-first distance (in samples, 8-connected with √2 diagonals, a chamfer
/// approximation of the Euclidean distance) from the cells where `src` is true, and the index
/// of the nearest source cell; `(∞, usize::MAX)` when there is no source.
pub(super) fn chamfer(w: usize, h: usize, src: &[bool]) -> (Vec<f32>, Vec<usize>) {
    let n = w * h;
    let mut d = vec![f32::INFINITY; n];
    let mut near = vec![usize::MAX; n];
    for i in 0..n {
        if src[i] {
            d[i] = 0.0;
            near[i] = i;
        }
    }
    // two raster passes of the 3 x 3 chamfer (Borgefors 1986, "Distance transformations in
    // digital images", CVGIP 34:344–371), carrying the nearest source
    let diag = std::f32::consts::SQRT_2;
    let fwd: [(i64, i64, f32); 4] = [(-1, 0, 1.0), (-1, -1, diag), (0, -1, 1.0), (1, -1, diag)];
    let bwd: [(i64, i64, f32); 4] = [(1, 0, 1.0), (1, 1, diag), (0, 1, 1.0), (-1, 1, diag)];
    for (pass, offs) in [(0, fwd), (1, bwd)] {
        for k in 0..n {
            let i = if pass == 0 { k } else { n - 1 - k };
            let (c, r) = ((i % w) as i64, (i / w) as i64);
            for (dc, dr, cost) in offs {
                let (nc, nr) = (c + dc, r + dr);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                    continue;
                }
                let j = nr as usize * w + nc as usize;
                if d[j] + cost < d[i] {
                    d[i] = d[j] + cost;
                    near[i] = near[j];
                }
            }
        }
    }
    (d, near)
}

/// Stream channels as smoothed centre lines (for drawing). Every cell of the flow grid with a
/// [`crate::render::terrain::stream_strength`] s > 0 of its contributing area (`acc` cells of
/// `cell_area` m²) is a channel cell; its part of the channel runs from the midpoint of the D8
/// step into it (from its upstream channel neighbour of largest area; from its own centre at a
/// channel head) to the midpoint of its D8 step out (its own centre at an outlet), as the
/// quadratic Bézier curve with the cell centre as control point, every centre first replaced by
/// the mean of the centres within two steps along the channel (upstream along the main stem; as
/// many steps on each side, so heads and outlets stay in place).
/// D8 paths are staircases of axis and diagonal steps in irregular runs; averaged along the
/// channel and with their corners cut (Chaikin's corner cutting, one round), a channel running
/// at 30° to the grid is drawn as a smooth line, not a staircase. `at(x, y, s, len)` is called at points of every curve at most
/// `spacing` m apart (window-local metres from `local`, the plan position of a cell centre),
/// `len` the length of curve (m) the point stands for (half of each chord beside it).
pub(super) fn stream_lines(acc: &Grid<f32>, dir: &Grid<u8>, m: &Grid<bool>, cell_area: f64, local: &dyn Fn(usize, usize) -> [f64; 2], spacing: f64, mut at: impl FnMut(f64, f64, f32, f64)) {
    let (w, h) = (acc.width, acc.height);
    let strength = |i: usize| if m.data[i] { crate::render::terrain::stream_strength((acc.data[i] as f64 * cell_area) as f32) } else { 0.0 };
    let s: Vec<f32> = (0..w * h).map(strength).collect();
    let down = |i: usize| crate::terrain::fields::downstream(dir, i);
    // the main upstream channel cell of every channel cell: the one of largest area
    let mut up: Vec<Option<usize>> = vec![None; w * h];
    for i in 0..w * h {
        if s[i] > 0.0 {
            if let Some(j) = down(i) {
                if up[j].is_none_or(|k| acc.data[i] > acc.data[k]) {
                    up[j] = Some(i);
                }
            }
        }
    }
    // every channel cell's centre smoothed along the channel: the mean of the centres of the
    // cells up to SMOOTH steps upstream (main stem) and as many downstream of it
    const SMOOTH: usize = 2;
    let centre = |i: usize| local(i % w, i / w);
    let xy = |i: usize| {
        let mut sum = centre(i);
        let mut k = 1.0;
        let (mut u, mut d) = (i, i);
        // as many steps upstream as downstream, so that heads and outlets stay where they are
        for _ in 0..SMOOTH {
            let (Some(nu), Some(nd)) = (up[u], down(d)) else { break };
            (u, d) = (nu, nd);
            let (qu, qd) = (centre(u), centre(d));
            sum = [sum[0] + qu[0] + qd[0], sum[1] + qu[1] + qd[1]];
            k += 2.0;
        }
        [sum[0] / k, sum[1] / k]
    };
    // smoothed once per channel cell (and per cell a channel drains into), not per curve
    let smooth: Vec<Option<[f64; 2]>> = (0..w * h).map(|i| (s[i] > 0.0 || up[i].is_some()).then(|| xy(i))).collect();
    let at_cell = |i: usize| smooth[i].unwrap_or_else(|| xy(i));
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    for i in 0..w * h {
        if s[i] <= 0.0 {
            continue;
        }
        let p = at_cell(i);
        let a = up[i].map_or(p, |k| mid(at_cell(k), p));
        let b = down(i).map_or(p, |j| mid(p, at_cell(j)));
        let len = (a[0] - p[0]).hypot(a[1] - p[1]) + (b[0] - p[0]).hypot(b[1] - p[1]);
        if len <= 0.0 {
            continue; // a lone channel cell (head and outlet): no line
        }
        let n = ((len / spacing.max(1e-3)).ceil() as usize).clamp(2, 256);
        let pts: Vec<[f64; 2]> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                let (u, v, z) = ((1.0 - t) * (1.0 - t), 2.0 * (1.0 - t) * t, t * t);
                [u * a[0] + v * p[0] + z * b[0], u * a[1] + v * p[1] + z * b[1]]
            })
            .collect();
        let chord = |k: usize| (pts[k + 1][0] - pts[k][0]).hypot(pts[k + 1][1] - pts[k][1]);
        for k in 0..=n {
            // the curves of consecutive cells meet at the midpoints: each end counts half
            let l = 0.5 * (if k > 0 { chord(k - 1) } else { 0.0 } + if k < n { chord(k) } else { 0.0 });
            at(pts[k][0], pts[k][1], s[i], l);
        }
    }
}

impl Landscape {
    /// The landscape of `site`. `full`: the whole terrain the site was cut from and the window
    /// `[col0, row0, width, height]` (cells of that terrain) it was cut with; `None`: the site
    /// alone. The margin drawn around the window is half its longer side, at most 2 km; beyond
    /// the end of the DEM's grid (or of the site alone) the ground is the DEM's mirror image
    /// ([`mirrored`]; until round 39 the edge samples were stretched outwards into streaks and
    /// a site alone faded out within [`EDGE_FADE_M`] of its edge: an island in the sky). The
    /// surroundings fade into the sky from 35 % of the margin to its end, and over
    /// [`EDGE_FADE_M`] at the edge of the DEM's no-data cells. Samples at most `max_cell_m` apart; inside the window their height
    /// is the site's [`SiteConditions::elevation_at_valid`], so trees stand on the ground drawn,
    /// and the window's no-data cells stay NaN: [`crate::render::terrain::from_ground`] leaves
    /// their quads out, so a DEM's no-data hole is drawn as a hole (the sky's colour behind it,
    /// no walls) in every view.
    /// Streams ([`crate::render::terrain::stream_strength`] of the D8 flow accumulation, drawn
    /// along corner-cut centre lines so that they do not show the D8 staircase) and
    /// wetness (topographic wetness index, [`crate::render::terrain::wetness`]) are computed on
    /// the terrain of the drawn area (`crate::terrain::fields`), so the flow from beyond the
    /// window counts.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when the window leaves `full`'s grid or `max_cell_m ≤ 0`.
    pub fn new(site: &SiteConditions, full: Option<(&crate::terrain::Terrain, [usize; 4])>, max_cell_m: f64, sea_level: f32) -> Result<Landscape> {
        use crate::terrain::fields;
        if !(max_cell_m > 0.0) {
            return Err(crate::Error::Invalid { context: "job::scene::Landscape".into(), field: "max_cell_m".into(), value: max_cell_m.to_string(), expected: "> 0 m".into() });
        }
        let f = ((site.cell_x_m.max(site.cell_y_m) / max_cell_m).ceil() as usize).clamp(1, 16);
        let (cx, cy) = (site.cell_x_m / f as f64, site.cell_y_m / f as f64);
        let (ex, ey) = site.extent_m();
        // the source terrain: the full DEM around the window, or the site itself
        let own;
        let (src, [c0, r0, ww, wh]) = match full {
            Some((t, w)) => {
                if w[0] + w[2] > t.elevation.width || w[1] + w[3] > t.elevation.height {
                    return Err(crate::Error::Invalid { context: t.source.clone(), field: "window".into(), value: format!("{w:?}"), expected: format!("inside {} x {}", t.elevation.width, t.elevation.height) });
                }
                (t, w)
            }
            None => {
                // the site's no-data cells NaN, so that its mirror image beyond the edge
                // keeps its holes (filled and faded below) instead of their 0 m
                let mut elevation = site.elevation_m.clone();
                let w = elevation.width;
                elevation.data.iter_mut().enumerate().filter(|(i, _)| site.is_no_data(site.held.col0 + i % w, site.held.row0 + i / w, sea_level)).for_each(|(_, z)| *z = f32::NAN);
                own = crate::terrain::Terrain { elevation, geo: site.geo.clone(), nodata: None, source: "site".into() };
                (&own, [0, 0, site.width(), site.height()])
            }
        };
        let (scx, scy) = (ex / ww as f64, ey / wh as f64);
        let margin = (0.5 * ex.max(ey)).min(2000.0);
        let (mx, my) = ((margin / cx).ceil() as usize, (margin / cy).ceil() as usize);
        let (nw, nh) = (((ex / cx).round() as usize) + 2 * mx, ((ey / cy).round() as usize) + 2 * my);
        let origin = [-(mx as f64 * cx), -(my as f64 * cy)];
        // the source cells under the drawn area, for the flow fields
        let sc0 = (c0 as f64 - margin / scx).floor().max(0.0) as usize;
        let sr0 = (r0 as f64 - margin / scy).floor().max(0.0) as usize;
        let sc1 = ((c0 + ww) as f64 + margin / scx).ceil().min(src.elevation.width as f64) as usize;
        let sr1 = ((r0 + wh) as f64 + margin / scy).ceil().min(src.elevation.height as f64) as usize;
        let sub = crate::terrain::io::window(src, sc0, sr0, sc1 - sc0, sr1 - sr0)?;
        let m = fields::mask(&sub, sea_level);
        let filled = fields::fill_depressions(&sub, &m);
        let dir = fields::flow_directions(&filled, &sub.geo, &m);
        let acc = fields::flow_accumulation(&dir, &m);
        let (slope, _) = fields::slope_aspect(&sub, &m);
        let twi = fields::twi(&acc, &slope, &sub.geo, &m);
        // source grid position (fractional column, row) of a window-local point
        let to_src = |x: f64, y: f64| (c0 as f64 + x / scx - 0.5, r0 as f64 + wh as f64 - y / scy - 0.5);
        // beyond the end of the source grid its mirror image ([`mirrored`]): the relief goes on
        // (a nearest-sample fill stretched the edge cells into streaks, trial 39)
        let src_at = |fc: f64, fr: f64| -> f32 {
            let g = &src.elevation;
            let (fc, fr) = (mirrored(fc, g.width), mirrored(fr, g.height));
            let (fc, fr) = (fc.clamp(0.0, (g.width - 1) as f64), fr.clamp(0.0, (g.height - 1) as f64));
            let (a, b) = (fc.floor() as usize, fr.floor() as usize);
            let (a1, b1) = ((a + 1).min(g.width - 1), (b + 1).min(g.height - 1));
            let (tx, ty) = ((fc - a as f64) as f32, (fr - b as f64) as f32);
            let v = g.get(a, b) * (1.0 - tx) * (1.0 - ty) + g.get(a1, b) * tx * (1.0 - ty) + g.get(a, b1) * (1.0 - tx) * ty + g.get(a1, b1) * tx * ty;
            v
        };
        let n = nw * nh;
        let mut heights = vec![f32::NAN; n];
        let mut stream = vec![0.0f32; n];
        let mut wet = vec![0.0f32; n];
        let mut outside = vec![0.0f64; n];
        let cell_area = scx * scy;
        for r in 0..nh {
            for c in 0..nw {
                let i = r * nw + c;
                let x = origin[0] + (c as f64 + 0.5) * cx;
                let y = origin[1] + (nh as f64 - r as f64 - 0.5) * cy;
                let inside = x >= 0.0 && y >= 0.0 && x <= ex && y <= ey;
                let (fc, fr) = to_src(x, y);
                // a no-data cell of the window stays NaN: a hole in the ground drawn, no walls
                // (round 34; it was drawn at the 0 m the site holds there: a walled shaft)
                heights[i] = if inside { site.elevation_at_valid(x, y, sea_level) } else { src_at(fc, fr) };
                let (dx, dy) = ((-x).max(x - ex).max(0.0), (-y).max(y - ey).max(0.0));
                outside[i] = dx.hypot(dy);
                let (sc, sr) = (fc.round() as i64 - sc0 as i64, fr.round() as i64 - sr0 as i64);
                if sc >= 0 && sr >= 0 && (sc as usize) < acc.width && (sr as usize) < acc.height {
                    let (sc, sr) = (sc as usize, sr as usize);
                    if *m.get(sc, sr) {
                        wet[i] = crate::render::terrain::wetness(*twi.get(sc, sr));
                    }
                }
            }
        }
        // window-local plan position of the centre of cell (c, r) of `sub`
        let local = |c: usize, r: usize| -> [f64; 2] { [((sc0 + c) as f64 - c0 as f64 + 0.5) * scx, (r0 as f64 + wh as f64 - (sr0 + r) as f64 - 0.5) * scy] };
        // every curve point splats its strength bilinearly onto the four samples around it,
        // weighted by the length of curve it stands for (so a line through sample centres
        // along an axis draws its strength there, and the strength-weighted centre of a column
        // lies on the line: bilinear weights keep the first moment), at most 1 where lines meet
        stream_lines(&acc, &dir, &m, cell_area, &local, 0.2 * cx.min(cy), |x, y, s, len| {
            let (fc, fr) = ((x - origin[0]) / cx - 0.5, nh as f64 - (y - origin[1]) / cy - 0.5);
            let (c, r) = (fc.floor(), fr.floor());
            let (tx, ty) = (fc - c, fr - r);
            for (dc, dr, wgt) in [(0.0, 0.0, (1.0 - tx) * (1.0 - ty)), (1.0, 0.0, tx * (1.0 - ty)), (0.0, 1.0, (1.0 - tx) * ty), (1.0, 1.0, tx * ty)] {
                let (cc, rr) = (c + dc, r + dr);
                if cc >= 0.0 && rr >= 0.0 && cc < nw as f64 && rr < nh as f64 {
                    stream[rr as usize * nw + cc as usize] += (s as f64 * wgt * len / cx.min(cy)) as f32;
                }
            }
        });
        stream.iter_mut().for_each(|v| *v = v.min(1.0));
        // fill the samples without ground beyond the window from the nearest ground (flat
        // aprons) and fade them; those inside the window stay holes
        let valid: Vec<bool> = heights.iter().map(|v| v.is_finite()).collect();
        let invalid: Vec<bool> = valid.iter().map(|v| !v).collect();
        let (d_out, near) = chamfer(nw, nh, &valid);
        let (d_in, _) = chamfer(nw, nh, &invalid);
        let step = cx.min(cy);
        let sstep = |e0: f64, e1: f64, v: f64| {
            let t = ((v - e0) / (e1 - e0)).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        };
        let mut fade = vec![0.0f32; n];
        for i in 0..n {
            if !valid[i] && outside[i] > 0.0 {
                heights[i] = if near[i] == usize::MAX { 0.0 } else { heights[near[i]] };
            }
            if outside[i] <= 0.0 {
                continue;
            }
            // signed distance to the edge of the ground: negative inside
            let sd = if valid[i] { -(d_in[i] as f64) * step } else { d_out[i] as f64 * step };
            let edge = sstep(-EDGE_FADE_M, 0.25 * EDGE_FADE_M, sd);
            fade[i] = sstep(0.35 * margin, margin, outside[i]).max(edge) as f32;
        }
        let ground = crate::render::terrain::GroundGrid {
            heights: Grid { width: nw, height: nh, data: heights },
            cell_x: cx as f32,
            cell_y: cy as f32,
            origin: [origin[0] as f32, origin[1] as f32],
            stream,
            wetness: wet,
            fade,
            focus: Some(([0.0, 0.0], [ex as f32, ey as f32])),
        };
        Ok(Landscape { ground, cover: LandCover { sea_level, ..LandCover::default() }, mirror_trees: true })
    }

    /// Puts the stem base of each of `instances` on the ground [`Landscape::mesh`] draws
    /// ([`crate::render::terrain::GroundGrid::height_at`]): trees placed at the site's bilinear
    /// elevation stood centimetres above or below the drawn triangles on twisted slopes (6 cm
    /// on the slope of the test `trees_stand_on_the_drawn_ground`; issue 32). Instances off the
    /// samples keep their height; those at the rim of a no-data hole, where the quad is left
    /// out, stand on the ground beside it ([`crate::render::terrain::GroundGrid::height_near`]).
    pub fn stand_on_ground(&self, instances: &mut [TreeInstance]) {
        for t in instances {
            if let Some(z) = self.ground.height_near(t.position[0], t.position[1]) {
                t.position[2] = z;
            }
        }
    }

    /// The mesh of the landscape coloured for a frame whose trees are `instances`: plan canopy
    /// cover per sample from their crowns ([`canopy_cover`]) turns grass into forest floor.
    ///
    /// Errors: as [`crate::render::terrain::from_ground`] (none for a grid built by [`Landscape::new`]).
    pub fn mesh(&self, instances: &[TreeInstance]) -> Result<TerrainMesh> {
        let g = &self.ground;
        let cov = canopy_cover(instances, g);
        let (w, h) = (g.heights.width, g.heights.height);
        let lookup = |x: f32, y: f32| {
            let c = ((x - g.origin[0]) / g.cell_x - 0.5).round();
            let r = (h as f32 - (y - g.origin[1]) / g.cell_y - 0.5).round();
            if c < 0.0 || r < 0.0 || c >= w as f32 || r >= h as f32 {
                return 0.0;
            }
            cov[r as usize * w + c as usize]
        };
        crate::render::terrain::from_ground(g, &self.cover, &lookup)
    }
}

/// Share of the surroundings' trees kept on a DEM sample beyond the window on a slope of
/// `slope_deg` at elevation `z` (m): all of them, except on slopes of bare rock (from
/// [`LandCover::rock_slope_deg`] + 2° to + 10°), above the tree line (from 100 m below
/// [`LandCover::tree_line`] to 100 m above) and at or below the sea.
pub(super) fn surroundings_keep(slope_deg: f32, z: f32, cover: &LandCover) -> f32 {
    if !(z > cover.sea_level) {
        return 0.0;
    }
    (1.0 - (slope_deg - cover.rock_slope_deg - 2.0) / 8.0).clamp(0.0, 1.0) * (1.0 - (z - cover.tree_line + 100.0) / 200.0).clamp(0.0, 1.0)
}

/// The eight mirror images of the window around it: (−1, 0, +1) per axis, the west / south
/// edge, none, the east / north edge.
pub(super) const MIRRORS: [(i8, i8); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];

impl Landscape {
    /// The trees drawn on the terrain beyond the simulated window, so that the window and its
    /// surroundings read as one landscape: the window's own trees (`instances` inside
    /// [`GroundGrid::focus`]: trees, saplings, all as drawn this frame) mirrored across its
    /// four edges and four corners, standing on the surroundings' ground.
    ///
    /// Why mirrors: the surroundings are not simulated, so the most honest stand-in is the
    /// window's own stand, in the same year, season and state of growth (bare land at year 0,
    /// saplings while the window has saplings, the same species patches, heights, gaps and
    /// composition later); a mirror image continues every crown and patch across the window's
    /// edge, so no seam or straight line shows there, and the trees go through the same
    /// renderer (billboards, canopy layer, shadows) as the window's. One mirror image per edge
    /// reaches as far beyond it as the window is wide, so it fills the drawn margin
    /// ([`Landscape::new`]: half the longer side) for windows up to twice as long as they are
    /// wide; beyond that the far part of the margin along the long edges stays unforested.
    ///
    /// An image is kept with probability [`surroundings_keep`] of the ground sample it lands on
    /// (slope, tree line; a hash of its id), so the forest keeps off bare rock and stays below
    /// the tree line, and not where the ground has wholly faded into the sky; it fades into the
    /// sky with that ground ([`TreeInstance::sky_fade`] = the sample's fade). Its id is the tree's
    /// with the image number (1..=8) in bits 48..52, so that it varies like a tree of its own
    /// and keeps its sapling flag ([`SAPLING_ID_BIT`]); `z` is the ground's height there
    /// (bilinear over the samples). Empty without a window, and when [`Landscape::mirror_trees`]
    /// is off.
    ///
    /// [`GroundGrid::focus`]: crate::render::terrain::GroundGrid::focus
    pub fn surroundings(&self, instances: &[TreeInstance]) -> Vec<TreeInstance> {
        let g = &self.ground;
        let Some((lo, hi)) = g.focus.filter(|_| self.mirror_trees) else { return Vec::new() };
        let (w, h) = (g.heights.width, g.heights.height);
        if w < 2 || h < 2 {
            return Vec::new();
        }
        // fractional sample coordinates (column, row) of a plan point
        let frac = |x: f32, y: f32| ((x - g.origin[0]) / g.cell_x - 0.5, h as f32 - (y - g.origin[1]) / g.cell_y - 0.5);
        let z = |c: usize, r: usize| *g.heights.get(c.min(w - 1), r.min(h - 1));
        let mut out = Vec::new();
        for t in instances {
            let [x, y, _] = t.position;
            if !(x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1]) {
                continue;
            }
            for (k, &(mx, my)) in MIRRORS.iter().enumerate() {
                let xs = match mx {
                    -1 => 2.0 * lo[0] - x,
                    1 => 2.0 * hi[0] - x,
                    _ => x,
                };
                let ys = match my {
                    -1 => 2.0 * lo[1] - y,
                    1 => 2.0 * hi[1] - y,
                    _ => y,
                };
                let (fc, fr) = frac(xs, ys);
                if !(fc >= 0.0 && fr >= 0.0 && fc <= (w - 1) as f32 && fr <= (h - 1) as f32) {
                    continue;
                }
                let (c, r) = (fc.floor() as usize, fr.floor() as usize);
                let (tx, ty) = (fc - c as f32, fr - r as f32);
                let zz = z(c, r) * (1.0 - tx) * (1.0 - ty) + z(c + 1, r) * tx * (1.0 - ty) + z(c, r + 1) * (1.0 - tx) * ty + z(c + 1, r + 1) * tx * ty;
                let (cn, rn) = (fc.round() as usize, fr.round() as usize);
                // central differences, one-sided at the grid's edge
                let (c0, c1, r0, r1) = (cn.saturating_sub(1), (cn + 1).min(w - 1), rn.saturating_sub(1), (rn + 1).min(h - 1));
                let dzdx = (z(c1, rn) - z(c0, rn)) / ((c1 - c0).max(1) as f32 * g.cell_x);
                let dzdy = (z(cn, r0) - z(cn, r1)) / ((r1 - r0).max(1) as f32 * g.cell_y);
                let slope = dzdx.hypot(dzdy).atan().to_degrees();
                let fade = g.fade.get(rn * w + cn).copied().unwrap_or(0.0);
                let id = t.id ^ ((k as u64 + 1) << 48);
                let keep = surroundings_keep(slope, zz, &self.cover);
                if !(keep > 0.0 && fade < 0.99) || crate::render::terrain::cell_hash((id & 0xFFFF_FFFF) as i64, (id >> 32) as i64, 0x5EED) >= keep {
                    continue;
                }
                // on the drawn ground (its triangles), not the samples' bilinear surface
                let zt = g.height_at(xs, ys).unwrap_or(zz);
                out.push(TreeInstance { position: [xs, ys, zt], id, sky_fade: fade, ..*t });
            }
        }
        out
    }
}
