//! The manifold repair of the critical 2x2x2 blocks and the thickening of sheets one voxel
//! thick ("Manifold repair" and "Sheets one voxel thick" in the module doc of [`super`]).

use super::{
    add, leaves_side, Builder, Face, Grid, Idx, LIPSCHITZ, MAX_SWEEPS, MIXED_SWEEPS, PATH_DEPTH,
    THICKEN_PASSES, THICKEN_ROUNDS,
};
use crate::implicit::Implicit;
use crate::{Error, Result};
use nalgebra::Point3;

/// A repair: set these voxels to `inside`, with `rep` (f there `frep`) as their representative.
struct Fix {
    voxels: Vec<Idx>,
    inside: bool,
    rep: Point3<f64>,
    frep: f64,
}

impl<I: Implicit + ?Sized> Builder<'_, I> {
    /// Is there a path of sign `inside` from voxel a's representative through the critical
    /// point `x` (half-voxel coordinates) to voxel b's? Returns None when there is, else a point
    /// of the other sign that blocks it.
    fn blocked(
        &mut self,
        a: Idx,
        x: Idx,
        b: Idx,
        inside: bool,
    ) -> Result<Option<(Point3<f64>, f64)>> {
        let sgn = if inside { -1.0 } else { 1.0 };
        let fx = self.probe(x);
        let px = self.grid.half_point(x);
        let (Some(va), Some(vb)) = (self.voxel(a)?, self.voxel(b)?) else {
            // Off-grid voxels are outside with no representative point.
            return Ok(if inside {
                Some((px, f64::INFINITY))
            } else {
                None
            });
        };
        let lip = LIPSCHITZ * va.g.norm().max(vb.g.norm());
        if sgn * fx <= 0.0 {
            return Ok(Some((px, fx)));
        }
        if let Some(hit) = leaves_side(self.f, va.rep, va.frep, px, fx, sgn, lip, PATH_DEPTH) {
            return Ok(Some(hit));
        }
        Ok(leaves_side(
            self.f, px, fx, vb.rep, vb.frep, sgn, lip, PATH_DEPTH,
        ))
    }

    /// Inside/outside of the eight voxels around grid vertex `v` ([`block_voxel`] order).
    fn block_classes(&mut self, v: Idx) -> Result<[bool; 8]> {
        let mut cls = [false; 8];
        for (c, cl) in cls.iter_mut().enumerate() {
            *cl = self.class(block_voxel(v, c))?;
        }
        Ok(cls)
    }

    /// The critical configuration at grid vertex `v` (if any) and its fix.
    fn check_vertex(&mut self, v: Idx, add_only: bool) -> Result<Option<Fix>> {
        let vox_at = |c: usize| block_voxel(v, c);
        let cls = self.block_classes(v)?;
        let vh = [2 * v[0], 2 * v[1], 2 * v[2]];
        // C1 on the six 2x2 slabs (one per grid edge at v).
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            for s in 0..2usize {
                let idx = |x: usize, y: usize| (s << a) | (x << b) | (y << c);
                let (q00, q11, q01, q10) = (idx(0, 0), idx(1, 1), idx(0, 1), idx(1, 0));
                if cls[q00] == cls[q11] && cls[q01] == cls[q10] && cls[q00] != cls[q01] {
                    let mut mid = vh;
                    mid[a] += 2 * s as i64 - 1;
                    let (ins, outs) = if cls[q00] {
                        ([q00, q11], [q01, q10])
                    } else {
                        ([q01, q10], [q00, q11])
                    };
                    let (ins, outs) = (ins.map(vox_at), outs.map(vox_at));
                    let block = if self.medial_pair(&ins) {
                        None
                    } else {
                        self.blocked(ins[0], mid, ins[1], true)?
                    };
                    return self
                        .single_fix(add_only || block.is_none(), ins, outs, mid, block)
                        .map(Some);
                }
            }
        }
        // C2: two voxels sharing only v, the other six of the other class.
        let count = cls.iter().filter(|&&x| x).count();
        if count == 2 || count == 6 {
            let minority = count == 2;
            if let Some(c) = (0..4).find(|&c| cls[c] == minority && cls[7 - c] == minority) {
                let pair = [vox_at(c), vox_at(7 - c)];
                let block = if minority && self.medial_pair(&pair) {
                    None
                } else {
                    self.blocked(pair[0], vh, pair[1], minority)?
                };
                let fix = if minority {
                    // Two inside voxels touching at v: join them by a face path, or drop one.
                    if add_only || block.is_none() {
                        self.path_fix(c, &vox_at, true, vh)?
                    } else {
                        self.single_fix(false, pair, pair, vh, block)?
                    }
                } else if block.is_none() && !add_only {
                    // Two outside voxels connected through v: open a face path between them.
                    self.path_fix(c, &vox_at, false, vh)?
                } else {
                    // Fill one of them.
                    self.single_fix(true, pair, pair, vh, block)?
                };
                return Ok(Some(fix));
            }
        }
        Ok(None)
    }

    /// Connect: add the outside voxel with the smaller f (representative: the critical point);
    /// else remove the inside voxel with the larger f (representative: the blocking point).
    /// Voxels off the grid cannot become inside, so the other fix is used for them.
    fn single_fix(
        &mut self,
        connect: bool,
        ins: [Idx; 2],
        outs: [Idx; 2],
        crit: Idx,
        block: Option<(Point3<f64>, f64)>,
    ) -> Result<Fix> {
        let crit_point = self.grid.half_point(crit);
        let fcrit = self.probe(crit);
        if connect {
            let f0 = self.centre_value(outs[0])?;
            let f1 = self.centre_value(outs[1])?;
            let pick = if f1 < f0 { outs[1] } else { outs[0] };
            if self.grid.key(pick).is_some() {
                let (rep, frep) = match block {
                    Some(b) if b.1 < 0.0 => b,
                    _ => (crit_point, fcrit),
                };
                return Ok(Fix {
                    voxels: vec![pick],
                    inside: true,
                    rep,
                    frep,
                });
            }
        }
        let f0 = self.centre_value(ins[0])?;
        let f1 = self.centre_value(ins[1])?;
        let pick = if f1 > f0 { ins[1] } else { ins[0] };
        let (rep, frep) = match block {
            Some(b) if b.1 > 0.0 => b,
            _ => (crit_point, fcrit),
        };
        Ok(Fix {
            voxels: vec![pick],
            inside: false,
            rep,
            frep,
        })
    }

    /// Sets the two middle voxels of the face path from block corner c to 7 - c to `inside`:
    /// the path with the smallest (adding) or largest (removing) sum of f.
    fn path_fix(
        &mut self,
        c: usize,
        vox_at: &impl Fn(usize) -> Idx,
        inside: bool,
        vh: Idx,
    ) -> Result<Fix> {
        let mut best: Option<(f64, Vec<Idx>)> = None;
        for (x, y) in [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)] {
            let m1 = c ^ (1 << x);
            let m2 = m1 ^ (1 << y);
            let (p1, p2) = (vox_at(m1), vox_at(m2));
            if inside && (self.grid.key(p1).is_none() || self.grid.key(p2).is_none()) {
                continue;
            }
            let s = self.centre_value(p1)? + self.centre_value(p2)?;
            let score = if inside { s } else { -s };
            if best.as_ref().is_none_or(|(b, _)| score < *b) {
                best = Some((score, vec![p1, p2]));
            }
        }
        let voxels = best
            .map(|b| b.1)
            .ok_or_else(|| Error::Numerical("voxel net repair: no path inside the grid".into()))?;
        let frep = self.probe(vh);
        Ok(Fix {
            voxels,
            inside,
            rep: self.grid.half_point(vh),
            frep,
        })
    }

    fn apply(&mut self, fix: Fix) -> Result<()> {
        for i in fix.voxels {
            if !self.set_voxel(i, fix.inside, fix.rep, fix.frep)? {
                continue;
            }
            if fix.inside {
                self.stats.repair_added += 1;
            } else {
                self.stats.repair_removed += 1;
            }
        }
        Ok(())
    }

    /// Grid edges used by an odd number of faces (the net is open there because a neighbouring
    /// voxel is still unknown): evaluates the voxels around them. Returns true when it did.
    fn close_open_edges(&mut self, faces: &[Face]) -> Result<bool> {
        let mut edges: Vec<(u64, u64)> = Vec::with_capacity(faces.len() * 4);
        for face in faces {
            let c = Self::face_corners(face);
            for m in 0..4 {
                let (p, q) = (Grid::vkey(c[m]), Grid::vkey(c[(m + 1) % 4]));
                edges.push((p.min(q), p.max(q)));
            }
        }
        edges.sort_unstable();
        let mut todo = Vec::new();
        let mut i = 0;
        while i < edges.len() {
            let mut j = i;
            while j < edges.len() && edges[j] == edges[i] {
                j += 1;
            }
            if (j - i) % 2 == 1 {
                let (p, q) = (Grid::unkey(edges[i].0), Grid::unkey(edges[i].1));
                let a = (0..3).find(|&a| p[a] != q[a]).unwrap_or(0);
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                for (db, dc) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let mut v = p;
                    v[b] -= db;
                    v[c] -= dc;
                    if let Some(k) = self.grid.key(v) {
                        if !self.vox.contains_key(&k) {
                            todo.push(k);
                        }
                    }
                }
            }
            i = j;
        }
        if todo.is_empty() {
            return Ok(false);
        }
        self.eval_many(todo)?;
        Ok(true)
    }

    pub(super) fn repair(&mut self) -> Result<()> {
        for sweep in 0..MAX_SWEEPS {
            let faces = self.faces();
            if self.close_open_edges(&faces)? {
                continue;
            }
            let mut verts: Vec<u64> = faces
                .iter()
                .flat_map(|f| Self::face_corners(f).map(Grid::vkey))
                .collect();
            verts.sort_unstable();
            verts.dedup();
            let add_only = sweep >= MIXED_SWEEPS;
            let mut fixes = 0;
            for vk in verts {
                let v = Grid::unkey(vk);
                for _ in 0..8 {
                    match self.check_vertex(v, add_only)? {
                        Some(fix) => {
                            self.apply(fix)?;
                            fixes += 1;
                        }
                        None => break,
                    }
                }
            }
            self.stats.repair_sweeps = sweep + 1;
            if fixes == 0 {
                return Ok(());
            }
        }
        Err(Error::Numerical(format!(
            "voxel net repair left non-manifold configurations after {MAX_SWEEPS} sweeps"
        )))
    }

    /// Grid vertices where the net would meet both sheets of a part one voxel thick
    /// (module doc, "Sheets one voxel thick"): along some axis a, one block voxel above the
    /// vertex is inside with the voxel below it outside (a face facing -a) while another
    /// below is inside with the one above it outside (a face facing +a), and the two inside
    /// voxels are joined through the vertex inside the material (a plate, not two parts with
    /// a gap between them). Each is fixed by setting inside the outside voxel with the smaller
    /// f of the two that thicken one of the faces' voxels along a (representative: that
    /// voxel's). Repeats until none is left (at most `THICKEN_PASSES` passes); returns the
    /// voxels added.
    fn thicken_sheets(&mut self) -> Result<usize> {
        let mut added = 0;
        for _ in 0..THICKEN_PASSES {
            let mut verts: Vec<u64> = self
                .faces()
                .iter()
                .flat_map(|f| Self::face_corners(f).map(Grid::vkey))
                .collect();
            verts.sort_unstable();
            verts.dedup();
            let mut fixes = 0;
            for vk in verts {
                let v = Grid::unkey(vk);
                if let Some((pick, rep, frep)) = self.two_sheet_fix(v)? {
                    if self.set_voxel(pick, true, rep, frep)? {
                        self.stats.sheet_voxels += 1;
                        fixes += 1;
                    }
                }
            }
            added += fixes;
            if fixes == 0 {
                break;
            }
        }
        Ok(added)
    }

    /// [`thicken_sheets`](Self::thicken_sheets) and the manifold repair in turn until the
    /// thickening adds nothing (at most `THICKEN_ROUNDS` rounds: the repair can expose new
    /// two-sheet vertices).
    pub(super) fn thicken_and_repair(&mut self) -> Result<()> {
        for _ in 0..THICKEN_ROUNDS {
            if self.thicken_sheets()? == 0 {
                break;
            }
            self.repair()?;
        }
        Ok(())
    }

    /// The voxel to set inside (already evaluated) and its representative point and value, for
    /// [`thicken_sheets`](Self::thicken_sheets) at grid vertex `v`, if it needs one.
    fn two_sheet_fix(&mut self, v: Idx) -> Result<Option<(Idx, Point3<f64>, f64)>> {
        let vox_at = |c: usize| block_voxel(v, c);
        let cls = self.block_classes(v)?;
        let vh = [2 * v[0], 2 * v[1], 2 * v[2]];
        for a in 0..3 {
            let bit = 1usize << a;
            // Lateral positions: block indices with bit a clear (lower layer).
            let lower: Vec<usize> = (0..8).filter(|c| c & bit == 0).collect();
            let down = lower.iter().find(|&&l| cls[l | bit] && !cls[l]);
            let up = lower.iter().find(|&&l| cls[l] && !cls[l | bit]);
            let (Some(&p), Some(&q)) = (down, up) else {
                continue;
            };
            let (upper_in, lower_in) = (vox_at(p | bit), vox_at(q));
            if self.blocked(upper_in, vh, lower_in, true)?.is_some() {
                continue;
            }
            // Thicken the upper voxel downward (into p) or the lower one upward (into q | bit).
            let (c0, c1) = (vox_at(p), vox_at(q | bit));
            let (f0, f1) = (self.centre_value(c0)?, self.centre_value(c1)?);
            let (pick, from) = if f1 < f0 {
                (c1, lower_in)
            } else {
                (c0, upper_in)
            };
            if self.grid.key(pick).is_none() {
                continue;
            }
            let Some(src) = self.voxel(from)? else {
                continue;
            };
            self.class(pick)?;
            return Ok(Some((pick, src.rep, src.frep)));
        }
        Ok(None)
    }
}

/// Voxel c = dx + 2 dy + 4 dz (each 0 or 1) of the 2x2x2 block around grid vertex `v`:
/// v + (dx - 1, dy - 1, dz - 1).
fn block_voxel(v: Idx, c: usize) -> Idx {
    add(
        v,
        [
            (c & 1) as i64 - 1,
            (c >> 1 & 1) as i64 - 1,
            (c >> 2) as i64 - 1,
        ],
    )
}
