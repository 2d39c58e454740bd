//! Ray tests against entities (docs/NAADF.md §11), shared by every traversal method.
//!
//! Entities live outside the static world: a method's world loop traces the static world
//! with its full AADF jumps, up to its world hit or to where the ray leaves the world.
//! Then the ray walks the hierarchy over the instances' world boxes ([`Bvh`], derived on
//! every machine from the instance records) between the time it entered the world and
//! that end, and each instance found is tested in its own frame with the decoded record:
//! `o' = R⁻¹(o − pos)`, `d' = R⁻¹ d` (a rotation, so `t` is the world distance), by the
//! same event-model DDA as the grid method ([`super::grid`]) over the entity's dense grid.
//!
//! An entity hit counts when the entity voxel is entered inside the world: at `t` no
//! earlier than where the ray enters the world (parts of an entity outside the world are
//! clipped) and strictly before the world hit (ties go to the world) or before the ray
//! leaves the world. The nearest hit wins; among entity hits at the same `t`, the lowest
//! id. An entity hit reports entity-local voxel and normal.
//!
//! The hierarchy's walk has tested each instance found against its padded world box; it is
//! then tested against its padded oriented box ([`Bounds`]), which rejects about half. The
//! rest are tested in the order the ray enters their boxes, so that the first hit usually
//! ends the search: once a box is entered after the best hit, so is every later one.
//! Neither the boxes, the hierarchy nor the order changes the result, only the work.
//!
//! [`EntityView::resolve_many`] does the same for a slice of rays, walking the hierarchy
//! for all of them as batches ([`crate::entity::bvh::batch`]).

use super::ray::{End, Hit, Ray, Visit, walk};
use crate::entity::bvh::WalkRay;
use crate::entity::bvh::batch::{BATCH, Scratch};
use crate::entity::pack::InstanceRecord;
use crate::entity::set::InstanceSet;
use crate::entity::{ENTITY_SOLID, TYPE_ALIGN};
use crate::world::World;
use smallvec::SmallVec;
use std::cell::RefCell;

/// What a method's world loop leaves to the instance test.
pub(crate) enum WorldPart {
    /// The final result: no instance can change it (the ray missed the world, ran out of
    /// steps, or asks only whether anything is in the way and hit the world).
    Done(Option<Hit>),
    /// A nearer instance may lie on the ray's span in the world.
    Open(OpenPart),
}

/// The world's hit, if any, and the ray's span in the world (from `t_entry` to the hit or
/// to where it leaves), over which a nearer instance may lie; `steps` the cells the world
/// loop visited.
#[derive(Clone, Copy)]
pub(crate) struct OpenPart {
    pub world: Option<Hit>,
    pub t_entry: f64,
    pub t_end: f64,
    pub steps: u32,
}

thread_local! {
    /// What tracing a slice reuses from one batch to the next, kept per thread.
    static SCRATCH: RefCell<SliceScratch> = RefCell::default();
}

/// The buffers a slice's batches reuse: the hierarchy walk's lists, and the pairs it met
/// linked per ray.
#[derive(Default)]
struct SliceScratch {
    walk: Scratch,
    by_ray: ByRay,
}

/// The pairs (ray, instance) a batch walk met, linked per ray: ray `j`'s first pair is
/// `head[j]`, the one after pair `p` is `next[p]` ([`ByRay::END`] ends a run). Cheaper
/// than sorting the pairs, which come in no particular order.
#[derive(Default)]
struct ByRay {
    head: Vec<u32>,
    next: Vec<u32>,
}

impl ByRay {
    const END: u32 = u32::MAX;

    /// Links `pairs` for rays `0..rays`.
    fn link(&mut self, pairs: &[(u32, u32)], rays: usize) {
        self.head.clear();
        self.head.resize(rays, Self::END);
        self.next.resize(pairs.len(), Self::END);
        for (p, &(j, _)) in pairs.iter().enumerate() {
            self.next[p] = self.head[j as usize];
            self.head[j as usize] = p as u32;
        }
    }

    /// The indices of ray `j`'s pairs.
    fn run(&self, j: usize) -> impl Iterator<Item = usize> + '_ {
        let first = Some(self.head[j]).filter(|&p| p != Self::END);
        std::iter::successors(first, |&p| Some(self.next[p as usize]).filter(|&q| q != Self::END)).map(|p| p as usize)
    }
}

/// An open ray of a batch as its instance test needs it: its index in the batch (its slot
/// in the output holds the world's hit) and its world part's span and steps. Kept apart from
/// the hit, which most rays never need again, so that a batch's list stays small.
struct Pending {
    i: u32,
    steps: u32,
    t_entry: f64,
    t_end: f64,
}

/// What a ray test reads: the instances (records, boxes and hierarchy) and the entity
/// types' voxels.
#[derive(Clone, Copy)]
pub(crate) struct EntityView<'a> {
    set: &'a InstanceSet,
    voxels: &'a [u32],
}

/// An owned copy of what the ray test reads (for the dense-grid method, which owns its
/// decode of the world).
pub(crate) struct OwnedEntities {
    set: InstanceSet,
    voxels: Vec<u32>,
}

impl OwnedEntities {
    /// A copy of `world`'s instances, or `None` if it has none.
    pub fn of(world: &World) -> Option<Self> {
        let v = world.entity_view()?;
        Some(OwnedEntities {
            set: v.set.clone(),
            voxels: v.voxels.to_vec(),
        })
    }

    /// The copy, as the view the ray test reads.
    pub fn view(&self) -> EntityView<'_> {
        EntityView {
            set: &self.set,
            voxels: &self.voxels,
        }
    }
}

impl<'a> EntityView<'a> {
    /// The final result of a trace: the world loop's `part`, or a nearer entity hit (the
    /// entity cells visited are added to the steps).
    pub fn resolve(&self, ray: &Ray, part: WorldPart) -> Option<Hit> {
        let open = match part {
            WorldPart::Done(hit) => return hit,
            WorldPart::Open(open) => open,
        };
        let mut found = SmallVec::<[u32; 8]>::new();
        let walk = WalkRay::new(ray.origin(), ray.dir(), open.t_entry, open.t_end);
        self.set.bvh.crossing(&walk, |k| found.push(k));
        self.settle(ray, &open, found)
    }

    /// [`EntityView::resolve`] for each ray of `rays` and its world part (`part` of the
    /// ray), the rays' walks of the hierarchy made in batches
    /// ([`crate::entity::bvh::batch`]).
    pub fn resolve_many(&self, rays: &[Ray], part: impl Fn(&Ray) -> WorldPart) -> Vec<Option<Hit>> {
        let mut out = Vec::with_capacity(rays.len());
        let mut walks = Vec::with_capacity(BATCH.min(rays.len()));
        let mut open = Vec::with_capacity(BATCH.min(rays.len()));
        for batch in rays.chunks(BATCH) {
            let first = out.len();
            walks.clear();
            open.clear();
            for (i, ray) in batch.iter().enumerate() {
                match part(ray) {
                    WorldPart::Done(hit) => out.push(hit),
                    WorldPart::Open(part) => {
                        walks.push(WalkRay::new(ray.origin(), ray.dir(), part.t_entry, part.t_end));
                        open.push(Pending {
                            i: i as u32,
                            steps: part.steps,
                            t_entry: part.t_entry,
                            t_end: part.t_end,
                        });
                        out.push(part.world);
                    }
                }
            }
            SCRATCH.with_borrow_mut(|SliceScratch { walk, by_ray }| {
                let found = self.set.bvh.crossing_many(&walks, walk);
                // The bounds and records of the instances met: fetched all at once here, their
                // cache misses overlap, where the tests below would wait for each in turn.
                for &(_, k) in found.iter() {
                    prefetch(&self.set.bounds[k as usize]);
                    prefetch(&self.set.records[k as usize]);
                }
                by_ray.link(found, walks.len());
                for (j, p) in open.iter().enumerate() {
                    let mut run = by_ray.run(j).map(|pair| found[pair].1).peekable();
                    if run.peek().is_some() {
                        let at = first + p.i as usize;
                        let part = OpenPart {
                            world: out[at],
                            t_entry: p.t_entry,
                            t_end: p.t_end,
                            steps: p.steps,
                        };
                        out[at] = self.settle(&batch[p.i as usize], &part, run);
                    }
                }
            });
        }
        out
    }

    /// The result of a ray whose walk of the hierarchy `found` these instances: the nearest
    /// of them that it hits, or the world part's hit.
    fn settle(&self, ray: &Ray, part: &OpenPart, found: impl IntoIterator<Item = u32>) -> Option<Hit> {
        let mut crossed = Crossed::new(self, ray, part.t_entry, part.t_end);
        for k in found {
            crossed.offer(k);
        }
        if crossed.list.is_empty() {
            return part.world;
        }
        self.nearest(ray, part.world, crossed, part.steps)
    }

    /// The nearest hit among `world` and the instances `crossed` found.
    fn nearest(&self, ray: &Ray, world: Option<Hit>, crossed: Crossed, mut steps: u32) -> Option<Hit> {
        let (t_entry, t_end) = (crossed.t_entry, crossed.t_end);
        let mut crossed = crossed.list;
        crossed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut best: Option<Hit> = None;
        for &(t_box, id, k) in &crossed {
            // Entity hits must come before the world's end (ties go to the world) and before
            // the best entity hit so far, or at its time with a lower id.
            let (limit, equal_ok) = match &best {
                Some(b) => (b.t, b.entity.is_some_and(|e| id < e)),
                None => (t_end, false),
            };
            if t_box > limit {
                break;
            }
            let rec = InstanceRecord::unpack(&self.set.records[k]);
            let local = self.set.bounds[k].local(ray);
            if let Some(h) = self.test(&local, &rec, t_entry, limit, equal_ok, &mut steps) {
                best = Some(h);
            }
        }
        best.or(world).map(|mut h| {
            h.steps = steps;
            h
        })
    }

    /// The first solid voxel of one instance entered at `t` in `[t_lo, limit)` (or
    /// `[t_lo, limit]` with `equal_ok`), for the ray `local` in the instance's frame.
    fn test(
        &self,
        local: &Ray,
        rec: &InstanceRecord,
        t_lo: f64,
        limit: f64,
        equal_ok: bool,
        steps: &mut u32,
    ) -> Option<Hit> {
        let base = rec.voxel_start as usize * TYPE_ALIGN;
        let [sx, sy, _] = rec.size.map(|v| v as usize);
        let walk = walk(local, rec.size, |c, t| {
            if t > limit || (t == limit && !equal_ok) {
                return Visit::Stop;
            }
            if t < t_lo {
                return Visit::Empty;
            }
            let i = base + c[0] as usize + sx * (c[1] as usize + sy * c[2] as usize);
            match self.voxels.get(i) {
                Some(&v) if v & ENTITY_SOLID != 0 => Visit::Solid((v & 0x7FFF) as u16),
                _ => Visit::Empty,
            }
        })?;
        match walk.end {
            End::Hit(mut h) => {
                *steps += h.steps;
                h.entity = Some(rec.id);
                Some(h)
            }
            End::Left { steps: s, .. } | End::Stopped { steps: s, .. } => {
                *steps += s;
                None
            }
        }
    }
}

/// The instances whose boxes a ray crosses before the world's end, as (time it enters the
/// boxes, id, instance), to be tested nearest first: a near hit lowers the limit, and once
/// a box is entered after the limit, so is every later one.
struct Crossed<'v, 'a> {
    view: &'v EntityView<'a>,
    o: [f64; 3],
    d: [f64; 3],
    t_entry: f64,
    t_end: f64,
    list: SmallVec<[(f64, u32, usize); 8]>,
}

impl<'v, 'a> Crossed<'v, 'a> {
    fn new(view: &'v EntityView<'a>, ray: &Ray, t_entry: f64, t_end: f64) -> Self {
        Crossed {
            view,
            o: ray.origin(),
            d: ray.dir(),
            t_entry,
            t_end,
            list: SmallVec::new(),
        }
    }

    /// Keeps instance `k` (whose world box the ray enters) if the ray enters its oriented
    /// box within the span.
    #[inline]
    fn offer(&mut self, k: u32) {
        let k = k as usize;
        let (Some(b), Some(r)) = (self.view.set.bounds.get(k), self.view.set.records.get(k)) else {
            return;
        };
        if let Some(t) = b.entry(self.o, self.d, self.t_entry, self.t_end) {
            self.list.push((t, r[4] & 0x3FFF, k));
        }
    }
}

/// Asks the processor to bring every cache line of `value` towards its first-level cache,
/// without waiting for them (a hint: it changes no result, only when memory is read).
#[inline(always)]
fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let first = (value as *const T).cast::<i8>();
        let last = size_of::<T>().saturating_sub(1);
        for offset in (0..last).step_by(64).chain([last]) {
            // SAFETY: the address lies inside `value`; a prefetch never faults or writes.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(first.add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

impl World {
    /// What a ray test reads of the entities, or `None` when there is no instance.
    #[inline]
    pub(crate) fn entity_view(&self) -> Option<EntityView<'_>> {
        self.entities.present().then(|| EntityView {
            set: self.entities.set(),
            voxels: &self.entities.type_voxels,
        })
    }
}
