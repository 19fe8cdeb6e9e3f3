//! The greedy quadtree refiner of Sec. 9.1, plus the stratified baseline.
//!
//! Every sample is the centre of a cell; a cell's importance is `metric × area`. A
//! binary heap holds the leaves; the most important ones are split into four children
//! whose centres are evaluated. Cells whose sample sees a different surface than a
//! neighbouring sample ("object boundary": object id, a depth off both samples'
//! tangent planes (`surfaces_differ`), or the side of a
//! bump map's terminator, `SampleValue::back_facing`) are *forced*: they
//! sort before every metric-driven cell and are split down to pixel size. Among
//! themselves they are ordered by the radiance jump across the boundary × area, the
//! same for every strategy, so that when the budget cannot refine every boundary the
//! visible ones go first. Forced splits may spend at most `Settings::boundary_share`
//! of the budget (default half); past it boundary cells compete on the strategy's
//! metric, so that at low budgets the strategies still differ.
//!
//! Determinism: heap keys are totally ordered (ties broken by cell id), splits are
//! taken in batches whose size depends only on the tree, and each batch is evaluated
//! with an order-preserving rayon `collect`. The result is therefore bit-identical for
//! any thread count.
//!
//! Batching is a (documented) departure from the paper's one-at-a-time greedy: up to
//! `leaves / 16` (at most 512) of the currently most important cells are split together
//! so that the estimator calls can run in parallel. The batch is a small fraction of the
//! leaves, so it takes cells the strict greedy would have split within a few steps anyway.

use super::{
    quadrant, surfaces_differ, Estimator, Sample, SampleSet, SampleValue, Settings, Strategy,
    SurfacePoint,
};
use crate::math::Vec2;
use crate::{Error, Result};
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::time::Instant;

const NONE: u32 = u32::MAX;
/// Smallest cell side that may still be created (pixels). Bounds the tree depth; with
/// budgets of at most 16 samples per pixel the refiner never gets near it.
const MIN_CELL: f32 = 1.0 / 64.0;
/// How far outside a cell the neighbour probes look (well below `MIN_CELL`).
const PROBE_EPS: f32 = 1.0 / 1024.0;
/// Largest accepted budget, in samples per pixel.
const MAX_BUDGET: f32 = 16.0;
/// The order in which a partial split (the last 1–3 samples of the budget) fills the
/// quadrants: the diagonal first, so that two samples still cover the square evenly.
const PARTIAL_ORDER: [u8; 4] = [0, 3, 1, 2];

/// Places exactly `round(settings.budget · width · height)` samples and evaluates them.
///
/// The paper's sparse start (one sample per 8×8 block) is coarsened to 16, 32, …
/// pixel blocks when the budget is smaller than the number of blocks. Splits add four
/// samples each; when fewer than four remain, the most important cell is split
/// *partially* (children in the order top-left, bottom-right, top-right, bottom-left), so
/// the count is always met exactly. Forced (object-boundary) splits are taken before any
/// metric-driven split until they have spent `boundary_share` of the budget; the rest
/// of the boundary then competes on the strategy's metric.
///
/// Errors: empty image, budget not in `(0, 16]` or rounding to zero samples, a
/// non-finite or negative depth tolerance, a zero block size, and `Durand`/`GradientVis`
/// when the estimator does not fill the field they need.
pub fn refine<E: Estimator + ?Sized>(
    estimator: &E,
    width: u32,
    height: u32,
    settings: &Settings,
) -> Result<SampleSet> {
    refine_with_progress(estimator, width, height, settings, &|_, _| {})
}

/// [`refine`], calling `progress(done, total)` after every evaluated batch (from the
/// calling thread), so that a caller with an expensive estimator can drive a progress bar.
pub fn refine_with_progress<E: Estimator + ?Sized>(
    estimator: &E,
    width: u32,
    height: u32,
    settings: &Settings,
    progress: &dyn Fn(usize, usize),
) -> Result<SampleSet> {
    refine_with_stats(estimator, width, height, settings, progress).map(|(set, _)| set)
}

/// Where the time of a [`refine`] went, in seconds of wall time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RefineStats {
    /// Inside the (parallel) estimator batches, idle threads at a batch's end included.
    pub evaluate_s: f64,
    /// Everything else: the quadtree's own work (neighbours, metrics, heap, splits).
    pub quadtree_s: f64,
}

/// [`refine_with_progress`], also returning how the time split between estimating
/// and the quadtree itself.
pub fn refine_with_stats<E: Estimator + ?Sized>(
    estimator: &E,
    width: u32,
    height: u32,
    settings: &Settings,
    progress: &dyn Fn(usize, usize),
) -> Result<(SampleSet, RefineStats)> {
    let start = Instant::now();
    let target = validate(width, height, settings)?;
    if settings.strategy == Strategy::Uniform {
        let (set, evaluate_s) =
            stratified(estimator, width, height, target, settings.depth_tolerance);
        progress(target, target);
        let quadtree_s = (start.elapsed().as_secs_f64() - evaluate_s).max(0.0);
        return Ok((
            set,
            RefineStats {
                evaluate_s,
                quadtree_s,
            },
        ));
    }
    let mut tree = Tree::new(width, height, settings, target);
    tree.start(estimator)?;
    progress(tree.cells.len(), target);
    tree.run(estimator, progress)?;
    let evaluate_s = tree.evaluate_s;
    let quadtree_s = (start.elapsed().as_secs_f64() - evaluate_s).max(0.0);
    Ok((
        tree.into_set(),
        RefineStats {
            evaluate_s,
            quadtree_s,
        },
    ))
}

fn option_error(option: &str, message: String) -> Error {
    Error::Option {
        option: option.into(),
        message,
    }
}

fn validate(width: u32, height: u32, settings: &Settings) -> Result<usize> {
    if width == 0 || height == 0 {
        return Err(option_error(
            "resolution",
            format!("image must not be empty, got {width}x{height}"),
        ));
    }
    let b = settings.budget;
    if !(b.is_finite() && b > 0.0 && b <= MAX_BUDGET) {
        return Err(option_error(
            "budget",
            format!("expected samples per pixel in (0, {MAX_BUDGET}], got {b}"),
        ));
    }
    let target = (b as f64 * width as f64 * height as f64).round() as usize;
    if target == 0 {
        return Err(option_error(
            "budget",
            format!("budget {b} gives no sample at all on a {width}x{height} image"),
        ));
    }
    if target >= NONE as usize {
        return Err(option_error(
            "budget",
            format!(
                "{target} samples exceed the quadtree's limit of {}",
                NONE - 1
            ),
        ));
    }
    if settings.block_size == 0 {
        return Err(option_error("block_size", "must be at least 1".into()));
    }
    let t = settings.depth_tolerance;
    if !(t.is_finite() && t >= 0.0) {
        return Err(option_error(
            "depth_tolerance",
            format!("expected a finite value >= 0, got {t}"),
        ));
    }
    Ok(target)
}

/// The `Uniform` baseline: `n` samples in `ny ≈ √(n·H/W)` rows, row `j` holding
/// `⌊(j+1)n/ny⌋ − ⌊jn/ny⌋` evenly spaced cells, each sample at its cell's centre.
fn stratified<E: Estimator + ?Sized>(
    est: &E,
    width: u32,
    height: u32,
    n: usize,
    depth_tolerance: f32,
) -> (SampleSet, f64) {
    let (w, h) = (width as f64, height as f64);
    let ny = ((n as f64 * h / w).sqrt().round() as usize).clamp(1, n);
    let mut cells = Vec::with_capacity(n);
    for j in 0..ny {
        let nj = (j + 1) * n / ny - j * n / ny;
        let y0 = (j as f64 * h / ny as f64) as f32;
        let y1 = ((j + 1) as f64 * h / ny as f64) as f32;
        for i in 0..nj {
            let x0 = (i as f64 * w / nj as f64) as f32;
            let x1 = ((i + 1) as f64 * w / nj as f64) as f32;
            cells.push((Vec2::new(x0, y0), Vec2::new(x1, y1)));
        }
    }
    let t = Instant::now();
    let values: Vec<SampleValue> = cells
        .par_iter()
        .map(|(a, b)| est.estimate((*a + *b) * 0.5))
        .collect();
    let evaluate_s = t.elapsed().as_secs_f64();
    let samples = cells
        .into_iter()
        .zip(values)
        .map(|((a, b), value)| Sample {
            pos: (a + b) * 0.5,
            cell_min: a,
            cell_max: b,
            split: 0,
            value,
        })
        .collect();
    let set = SampleSet {
        width,
        height,
        samples,
        depth_tolerance,
    };
    (set, evaluate_s)
}

#[derive(Clone, Debug)]
struct Cell {
    min: Vec2,
    max: Vec2,
    pos: Vec2,
    parent: u32,
    children: [u32; 4],
    split: u8,
    /// Importance per unit area (before the optional importance weight).
    metric: f32,
    forced: bool,
    /// Largest radiance jump |ΔI| to a neighbour on another surface: orders forced
    /// cells (the same for every strategy) when the budget cannot refine every
    /// boundary to pixel size.
    jump: f32,
    /// Bumped whenever the heap key changes; older heap entries are skipped.
    version: u32,
}

impl Cell {
    fn new(min: Vec2, max: Vec2, parent: u32) -> Self {
        Self {
            min,
            max,
            pos: (min + max) * 0.5,
            parent,
            children: [NONE; 4],
            split: 0,
            metric: 0.0,
            forced: false,
            jump: 0.0,
            version: 0,
        }
    }

    fn size(&self) -> f32 {
        let e = self.max - self.min;
        e.x.max(e.y)
    }

    fn area(&self) -> f32 {
        let e = self.max - self.min;
        e.x * e.y
    }

    /// Splitting must not create children below `MIN_CELL`.
    fn splittable(&self) -> bool {
        let e = self.max - self.min;
        e.x.min(e.y) * 0.5 >= MIN_CELL
    }
}

/// A heap entry; the max-heap pops forced cells first, then the largest importance,
/// then the largest area, then the oldest cell.
#[derive(Clone, Copy, Debug)]
struct Entry {
    forced: bool,
    key: f32,
    area: f32,
    id: u32,
    version: u32,
}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        self.forced
            .cmp(&o.forced)
            .then(self.key.total_cmp(&o.key))
            .then(self.area.total_cmp(&o.area))
            .then(o.id.cmp(&self.id))
            .then(self.version.cmp(&o.version))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}

impl Eq for Entry {}

/// Batches at least this large are compared with their neighbours in parallel.
const PARALLEL_MIN: usize = 256;

/// How a new sample relates to one neighbour.
#[derive(Clone, Copy, Debug)]
enum Link {
    /// Another surface, with this radiance jump |ΔI|.
    Boundary(f32),
    /// The same surface, with this pair metric.
    Pair(f32),
}

/// A new sample's links to its (at most nine) neighbours.
#[derive(Clone, Copy, Debug)]
struct Comparisons {
    links: [(u32, Link); 9],
    len: usize,
}

impl Default for Comparisons {
    fn default() -> Self {
        Self {
            links: [(NONE, Link::Pair(0.0)); 9],
            len: 0,
        }
    }
}

struct Tree {
    width: u32,
    height: u32,
    settings: Settings,
    target: usize,
    block: f32,
    nbx: usize,
    nby: usize,
    cells: Vec<Cell>,
    values: Vec<SampleValue>,
    /// `own_metric` of every evaluated sample, computed once.
    own: Vec<f32>,
    /// What the boundary test reads of every evaluated sample, built once: each is
    /// compared with up to nine neighbours, and this is a third of a `SampleValue`.
    surface: Vec<SurfacePoint>,
    heap: BinaryHeap<Entry>,
    leaves: usize,
    dirty: Vec<u32>,
    is_dirty: Vec<bool>,
    /// Wall time spent in `evaluate`.
    evaluate_s: f64,
    /// Samples created by forced splits so far, and the most they may create
    /// (`boundary_share × target`).
    forced_spent: usize,
    forced_cap: usize,
}

impl Tree {
    fn new(width: u32, height: u32, settings: &Settings, target: usize) -> Self {
        let mut block = settings.block_size as u64;
        let blocks = |b: u64| (width as u64).div_ceil(b) * (height as u64).div_ceil(b);
        while blocks(block) > target as u64 {
            block *= 2;
        }
        let nbx = (width as u64).div_ceil(block) as usize;
        let nby = (height as u64).div_ceil(block) as usize;
        Self {
            width,
            height,
            settings: *settings,
            target,
            block: block as f32,
            nbx,
            nby,
            cells: Vec::with_capacity(target),
            values: Vec::with_capacity(target),
            own: Vec::with_capacity(target),
            surface: Vec::with_capacity(target),
            heap: BinaryHeap::new(),
            leaves: 0,
            dirty: Vec::new(),
            is_dirty: Vec::new(),
            evaluate_s: 0.0,
            forced_spent: 0,
            forced_cap: (f64::from(settings.boundary_share.clamp(0.0, 1.0)) * target as f64)
                as usize,
        }
    }

    /// Whether forced splits may still spend `n` more samples.
    fn boundary_budget_left(&self, n: usize) -> bool {
        self.forced_spent + n <= self.forced_cap
    }

    /// The sparse uniform start: one sample at the centre of every block (clipped to
    /// the image at the right and bottom borders).
    fn start<E: Estimator + ?Sized>(&mut self, est: &E) -> Result<()> {
        let (w, h, b) = (self.width as f32, self.height as f32, self.block);
        for j in 0..self.nby {
            for i in 0..self.nbx {
                let min = Vec2::new(i as f32 * b, j as f32 * b);
                let max = Vec2::new((min.x + b).min(w), (min.y + b).min(h));
                self.cells.push(Cell::new(min, max, NONE));
            }
        }
        let n = self.cells.len();
        self.evaluate(est, 0);
        self.check_fields()?;
        self.leaves = n;
        self.process_new(0, n);
        Ok(())
    }

    /// `Durand` and `GradientVis` read renderer-provided fields; fail early and clearly
    /// when the estimator does not provide them.
    fn check_fields(&self) -> Result<()> {
        let (missing, field) = match self.settings.strategy {
            Strategy::Durand => (self.values.iter().any(|v| v.durand.is_none()), "durand"),
            Strategy::GradientVis => (
                self.values.iter().any(|v| v.vis_gradient.is_none()),
                "vis_gradient",
            ),
            _ => (false, ""),
        };
        if missing {
            return Err(option_error(
                "strategy",
                format!(
                    "strategy '{}' needs SampleValue::{field}, which this estimator does not fill",
                    self.settings.strategy.name()
                ),
            ));
        }
        Ok(())
    }

    /// Evaluates the cells from `first` on, in parallel, keeping their order.
    fn evaluate<E: Estimator + ?Sized>(&mut self, est: &E, first: usize) {
        let t = Instant::now();
        let new: Vec<SampleValue> = self.cells[first..]
            .par_iter()
            .map(|c| est.estimate(c.pos))
            .collect();
        self.values.extend(new);
        self.evaluate_s += t.elapsed().as_secs_f64();
    }

    fn run<E: Estimator + ?Sized>(
        &mut self,
        est: &E,
        progress: &dyn Fn(usize, usize),
    ) -> Result<()> {
        while self.cells.len() < self.target {
            let remaining = self.target - self.cells.len();
            let first = self.cells.len();
            if remaining >= 4 {
                let batch = (self.leaves / 16).clamp(1, 512).min(remaining / 4);
                let mut taken = 0;
                while taken < batch {
                    let Some(id) = self.pop() else { break };
                    self.split(id, 4);
                    taken += 1;
                }
                if taken == 0 {
                    return Err(self.exhausted());
                }
            } else {
                let Some(id) = self.pop() else {
                    return Err(self.exhausted());
                };
                self.split(id, remaining);
            }
            self.evaluate(est, first);
            let n = self.cells.len();
            self.process_new(first, n);
            progress(n, self.target);
        }
        Ok(())
    }

    fn exhausted(&self) -> Error {
        option_error(
            "budget",
            format!(
                "no cell left to refine after {} of {} samples",
                self.cells.len(),
                self.target
            ),
        )
    }

    /// Pops the most important valid leaf (skipping stale entries). Once the
    /// boundary share is spent, a forced entry goes back as an ordinary one.
    fn pop(&mut self) -> Option<u32> {
        while let Some(e) = self.heap.pop() {
            let c = &self.cells[e.id as usize];
            if c.version != e.version || c.split != 0 {
                continue;
            }
            if e.forced && !self.boundary_budget_left(4) {
                self.push(e.id);
                continue;
            }
            if e.forced {
                self.forced_spent += 4;
            }
            return Some(e.id);
        }
        None
    }

    /// Creates `count` children of `id` (all four, or a partial split in
    /// `PARTIAL_ORDER`). Their values are filled in by the following `evaluate`.
    fn split(&mut self, id: u32, count: usize) {
        let parent = self.cells[id as usize].clone();
        for &q in PARTIAL_ORDER.iter().take(count) {
            let (min, max) = quadrant(parent.min, parent.max, parent.pos, q);
            let child = self.cells.len() as u32;
            self.cells.push(Cell::new(min, max, id));
            let p = &mut self.cells[id as usize];
            p.children[q as usize] = child;
            p.split |= 1 << q;
        }
        self.leaves += count - 1;
    }

    /// The cell whose sample "owns" point `p`: the deepest cell containing it.
    fn owner(&self, p: Vec2) -> u32 {
        let i = ((p.x / self.block) as usize).min(self.nbx - 1);
        let j = ((p.y / self.block) as usize).min(self.nby - 1);
        let mut c = (j * self.nbx + i) as u32;
        loop {
            let cell = &self.cells[c as usize];
            let q = (p.x >= cell.pos.x) as usize | (((p.y >= cell.pos.y) as usize) << 1);
            let child = cell.children[q];
            if child == NONE {
                return c;
            }
            c = child;
        }
    }

    /// The neighbouring cells of `id`: the owners of eight points just outside its
    /// edges (midpoints and corners), plus its parent. Distinct, excluding `id`.
    fn neighbours(&self, id: u32, out: &mut Vec<u32>) {
        out.clear();
        let c = &self.cells[id as usize];
        let (x0, x1) = (c.min.x - PROBE_EPS, c.max.x + PROBE_EPS);
        let (y0, y1) = (c.min.y - PROBE_EPS, c.max.y + PROBE_EPS);
        let (cx, cy) = (c.pos.x, c.pos.y);
        let probes = [
            (x0, cy),
            (x1, cy),
            (cx, y0),
            (cx, y1),
            (x0, y0),
            (x1, y0),
            (x0, y1),
            (x1, y1),
        ];
        let (w, h) = (self.width as f32, self.height as f32);
        for (x, y) in probes {
            if x < 0.0 || y < 0.0 || x >= w || y >= h {
                continue;
            }
            let n = self.owner(Vec2::new(x, y));
            if n != id && !out.contains(&n) {
                out.push(n);
            }
        }
        if c.parent != NONE && !out.contains(&c.parent) {
            out.push(c.parent);
        }
    }

    /// The metric a sample has on its own (strategies that need no neighbours).
    fn own_metric(&self, v: &SampleValue) -> f32 {
        match self.settings.strategy {
            Strategy::Gradient => v.gradient_norm_denoised(),
            Strategy::GradientVis => {
                v.gradient_norm_denoised() + v.vis_gradient.unwrap_or(0.0).abs()
            }
            Strategy::Durand => v.durand.unwrap_or(0.0).abs(),
            Strategy::Uniform | Strategy::Variance | Strategy::SecondOrder => 0.0,
        }
    }

    /// The metric two neighbouring samples of one surface give each other.
    fn pair_metric(&self, a: u32, b: u32) -> f32 {
        let (va, vb) = (&self.values[a as usize], &self.values[b as usize]);
        let d = self.cells[a as usize]
            .pos
            .distance(self.cells[b as usize].pos);
        if d <= 0.0 {
            return 0.0;
        }
        match self.settings.strategy {
            // Sec. 9.2: the intensity difference of neighbours is a central difference
            // (less the estimators' noise, so that fireflies do not draw samples).
            Strategy::Variance => va.contrast_denoised(vb) / d,
            // |J_a − J_b| / d ≈ |H d̂|: a Hessian estimate from analytic gradients
            // (the second-order criterion of Sec. 9.3).
            Strategy::SecondOrder => {
                ((va.grad_u - vb.grad_u).length_squared()
                    + (va.grad_v - vb.grad_v).length_squared())
                .sqrt()
                    / d
            }
            // The analytic gradient is a point value: a cell's gradient magnitude is
            // estimated as the largest, over the segments to its neighbours, of the
            // mean of the two ends' |∇I| (the trapezoid rule along the segment), so
            // that a bump whose slope vanishes exactly at a sample still counts, and a
            // single noisy gradient lends its neighbours half its value, not all of it.
            Strategy::Gradient | Strategy::GradientVis => {
                0.5 * (self.own[a as usize] + self.own[b as usize])
            }
            _ => 0.0,
        }
    }

    fn mark_dirty(&mut self, id: u32) {
        let i = id as usize;
        if self.is_dirty.len() <= i {
            self.is_dirty.resize(self.cells.len().max(i + 1), false);
        }
        if !self.is_dirty[i] {
            self.is_dirty[i] = true;
            self.dirty.push(id);
        }
    }

    fn force(&mut self, id: u32, jump: f32) {
        let c = &mut self.cells[id as usize];
        if c.split == 0 && c.size() > 1.0 + 1e-4 && c.splittable() && (!c.forced || jump > c.jump) {
            c.forced = true;
            c.jump = c.jump.max(if jump.is_finite() { jump } else { 0.0 });
            self.mark_dirty(id);
        }
    }

    fn raise(&mut self, id: u32, m: f32) {
        let c = &mut self.cells[id as usize];
        if c.split == 0 && m > c.metric {
            c.metric = m;
            self.mark_dirty(id);
        }
    }

    /// What the comparisons of new sample `id` with its neighbours ask for: each
    /// neighbour with a radiance jump (another surface: force both) or a pair metric
    /// (raise both). Read-only, so a batch is analysed in parallel.
    fn compare_with_neighbours(&self, id: u32, pairs: bool) -> Comparisons {
        let mut nb = Vec::with_capacity(9);
        self.neighbours(id, &mut nb);
        let mut out = Comparisons::default();
        let tol = self.settings.depth_tolerance;
        let here = &self.surface[id as usize];
        for &n in &nb {
            let link = if surfaces_differ(here, &self.surface[n as usize], tol) {
                let (va, vb) = (&self.values[id as usize], &self.values[n as usize]);
                Link::Boundary(va.contrast_denoised(vb))
            } else if pairs {
                Link::Pair(self.pair_metric(id, n))
            } else {
                continue;
            };
            out.links[out.len] = (n, link);
            out.len += 1;
        }
        out
    }

    /// Scores the cells `first..end` (just evaluated): own metric, comparisons with
    /// neighbours (boundaries and pair metrics, which may also raise the neighbours),
    /// then (re)queues every cell whose key changed. The comparisons are computed in
    /// parallel and applied in cell order, so the result does not depend on threads.
    fn process_new(&mut self, first: usize, end: usize) {
        for id in first..end {
            let own = self.own_metric(&self.values[id]);
            self.own.push(own);
            let surface = self.values[id].surface_point(self.cells[id].pos);
            self.surface.push(surface);
            self.cells[id].metric = own.max(0.0);
            self.mark_dirty(id as u32);
        }
        let pairs = !matches!(self.settings.strategy, Strategy::Uniform | Strategy::Durand);
        let this = &*self;
        let compare = |id: u32| this.compare_with_neighbours(id, pairs);
        let ids = first as u32..end as u32;
        let found: Vec<Comparisons> = if end - first >= PARALLEL_MIN {
            ids.into_par_iter().map(compare).collect()
        } else {
            ids.map(compare).collect()
        };
        for (id, c) in (first as u32..).zip(found) {
            for &(n, link) in &c.links[..c.len] {
                match link {
                    Link::Boundary(jump) => {
                        self.force(id, jump);
                        self.force(n, jump);
                    }
                    Link::Pair(m) => {
                        self.raise(id, m);
                        self.raise(n, m);
                    }
                }
            }
        }
        let dirty = std::mem::take(&mut self.dirty);
        for &id in &dirty {
            self.is_dirty[id as usize] = false;
            self.push(id);
        }
        self.dirty = dirty;
        self.dirty.clear();
    }

    fn push(&mut self, id: u32) {
        let weight = self.values[id as usize].importance.map_or(1.0, |w| {
            if w.is_finite() {
                w.max(0.0)
            } else {
                0.0
            }
        });
        let c = &mut self.cells[id as usize];
        if c.split != 0 || !c.splittable() {
            return;
        }
        c.version += 1;
        let metric = if c.metric.is_finite() { c.metric } else { 0.0 };
        let area = c.area();
        let forced = c.forced && self.forced_spent + 4 <= self.forced_cap;
        // Past the boundary share, a boundary cell's jump still counts as the
        // contrast |ΔI| over its size, the metric a finite difference would give it.
        let metric = if c.forced {
            metric.max(c.jump / c.size())
        } else {
            metric
        };
        let key = if forced {
            c.jump * area
        } else {
            metric * weight * area
        };
        self.heap.push(Entry {
            forced,
            key,
            area,
            id,
            version: c.version,
        });
    }

    fn into_set(self) -> SampleSet {
        let samples = self
            .cells
            .iter()
            .zip(self.values)
            .map(|(c, value)| Sample {
                pos: c.pos,
                cell_min: c.min,
                cell_max: c.max,
                split: c.split,
                value,
            })
            .collect();
        SampleSet {
            width: self.width,
            height: self.height,
            samples,
            depth_tolerance: self.settings.depth_tolerance,
        }
    }
}
