//! One update of the blur shell: four passes over fixed chunks (positions, face normals,
//! vertex normals and facing, the per-polygon step).
use rayon::prelude::*;

use super::blur_shell::{check_rows, BlurShell, Hot, CHUNK, NEVER, ON_SILHOUETTE};
use crate::contour::{
    face_edge, face_normals_into, facing, MAX_COORD, MAX_NORMAL, NEUTRAL, NO_EDGE,
};
use crate::error::Result;
use crate::mesh::face_normal;

/// A raw pointer shared by the scatter of pass A; each row writes its own slot.
struct SharedSlots<T>(*mut T);
unsafe impl<T: Send> Sync for SharedSlots<T> {}
unsafe impl<T: Send> Send for SharedSlots<T> {}

impl BlurShell {
    /// Feed the mesh's world positions (V,3) and optionally its normals (V,3) at one update.
    /// Errors name `vertices` or `normals` (wrong count, NaN or inf, beyond `MAX_COORD` /
    /// `MAX_NORMAL`); the state is then unchanged.
    pub fn update(&mut self, vertices: &[[f64; 3]], normals: Option<&[[f64; 3]]>) -> Result<()> {
        if vertices.len() != self.n_vertices {
            return check_rows(vertices, self.n_vertices, "vertices", self.parallel());
        }
        if let Some(nr) = normals {
            if nr.len() != self.n_vertices {
                return check_rows(nr, self.n_vertices, "normals", self.parallel());
            }
        }
        let spare = self.spare;
        if let Some(bad) = self.scatter_inputs(vertices, normals, spare) {
            return bad;
        }
        if normals.is_none() {
            self.face_normals(spare);
        }
        self.vertex_facing(spare, normals.is_some());
        let slot = (self.updates % self.opts.subdivisions as u64) as usize;
        self.spare = std::mem::replace(&mut self.buf_of_slot[slot], spare);
        self.step_faces(slot);
        self.updates += 1;
        Ok(())
    }

    /// Pass A: float32 positions (and given normals) into the spare buffers, checking
    /// finiteness on the way. The caller's rows are read in order and scattered to their
    /// internal slots (stores do not stall on cache misses as gathered loads do). `Some`: the
    /// error naming the argument with a bad value (the state is unchanged but for the spare
    /// buffers).
    fn scatter_inputs(
        &mut self,
        vertices: &[[f64; 3]],
        normals: Option<&[[f64; 3]]>,
        spare: usize,
    ) -> Option<Result<()>> {
        let par = self.parallel();
        let inv = &self.loc.inv;
        if scatter_f32(vertices, inv, &mut self.pos_bufs[spare], MAX_COORD, par) {
            return Some(check_rows(vertices, self.n_vertices, "vertices", par));
        }
        let nr = normals?;
        if scatter_f32(nr, inv, &mut self.nrm_bufs[spare], MAX_NORMAL, par) {
            return Some(check_rows(nr, self.n_vertices, "normals", par));
        }
        None
    }

    /// Pass B: the face normals of the positions in buffer `spare`.
    fn face_normals(&mut self, spare: usize) {
        let cur = &self.pos_bufs[spare];
        if self.parallel() {
            face_normals_into(cur, &self.loc.bfaces, &mut self.face_n);
        } else {
            for (o, f) in self.face_n.iter_mut().zip(&self.loc.bfaces) {
                *o = face_normal(cur, f);
            }
        }
    }

    /// Pass C: vertex normals (unless `given`) and each vertex's facing against the previous
    /// update's positions (neutral at the first update).
    fn vertex_facing(&mut self, spare: usize, given: bool) {
        let par = self.parallel();
        let (n, s) = (self.updates, self.opts.subdivisions as u64);
        let prev = (n > 0).then(|| &self.pos_bufs[self.buf_of_slot[((n - 1) % s) as usize]]);
        let cur = &self.pos_bufs[spare];
        let (face_n, vf) = (&self.face_n, &self.loc.vf);
        let nb = &mut self.nrm_bufs[spare];
        let pass_c = |(c, (fa, nb)): (usize, (&mut [i8], &mut [[f32; 3]]))| {
            let base = c * CHUNK;
            for (i, (out, nb)) in fa.iter_mut().zip(nb).enumerate() {
                let v = base + i;
                let nrm = if given {
                    *nb
                } else {
                    let n = vf.normal(v, face_n);
                    *nb = n;
                    n
                };
                *out = match prev {
                    Some(pr) => facing(nrm, cur[v], pr[v]),
                    None => NEUTRAL,
                };
            }
        };
        if par {
            self.facing
                .par_chunks_mut(CHUNK)
                .zip(nb.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(pass_c);
        } else {
            self.facing
                .chunks_mut(CHUNK)
                .zip(nb.chunks_mut(CHUNK))
                .enumerate()
                .for_each(pass_c);
        }
    }

    /// Pass D: each face's silhouette edge, state, ring element in row `slot` (and the birth
    /// element in the previous row).
    fn step_faces(&mut self, slot: usize) {
        let s = self.opts.subdivisions as usize;
        let nf = self.faces.len();
        let par = self.parallel();
        let (row, prev_row): (&mut [u8], &mut [u8]) = if s == 1 {
            (&mut self.ring[..], &mut self.scratch_row)
        } else {
            let pslot = (slot + s - 1) % s;
            let (lo_slot, hi_slot) = (slot.min(pslot), slot.max(pslot));
            let (a, b) = self.ring.split_at_mut(hi_slot * nf);
            let (lo_row, hi_row) = (&mut a[lo_slot * nf..(lo_slot + 1) * nf], &mut b[..nf]);
            if slot > pslot {
                (hi_row, lo_row)
            } else {
                (lo_row, hi_row)
            }
        };
        let (facing_v, faces, mask) = (&self.facing, &self.loc.ifaces, self.mask.as_deref());
        let h = self.opts.hysteresis;
        let n = self.updates as u32;
        type Rows<'a> = (((&'a mut [u8], &'a mut [Hot]), &'a mut [u8]), &'a mut [u8]);
        let pass_d = |(c, (((fades, hots), row), prow)): (usize, Rows<'_>)| {
            let base = c * CHUNK;
            for i in 0..fades.len() {
                let f = base + i;
                let on = mask.is_none_or(|m| m[f]);
                let code = if on {
                    face_edge(facing_v, &faces[f])
                } else {
                    NO_EDGE
                };
                if code == NO_EDGE && fades[i] as usize >= s {
                    continue; // no strip and no edge: nothing changes
                }
                let step = Step { code, s, h, n };
                step.apply(&mut fades[i], &mut hots[i], &mut row[i], &mut prow[i]);
            }
        };
        if par {
            self.fade
                .par_chunks_mut(CHUNK)
                .zip(self.hot.par_chunks_mut(CHUNK))
                .zip(row.par_chunks_mut(CHUNK))
                .zip(prev_row.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(pass_d);
        } else {
            self.fade
                .chunks_mut(CHUNK)
                .zip(self.hot.chunks_mut(CHUNK))
                .zip(row.chunks_mut(CHUNK))
                .zip(prev_row.chunks_mut(CHUNK))
                .enumerate()
                .for_each(pass_d);
        }
    }
}

/// Float32 copies of `rows` scattered to `out[inv[i]]`, in parallel; true if a value is NaN,
/// inf or beyond `lim` in magnitude (then `out` is partly written: callers write only to a
/// spare buffer).
fn scatter_f32(rows: &[[f64; 3]], inv: &[u32], out: &mut [[f32; 3]], lim: f64, par: bool) -> bool {
    if !par {
        let mut bad = false;
        for (p, &dst) in rows.iter().zip(inv) {
            bad |= !(p[0].abs() <= lim && p[1].abs() <= lim && p[2].abs() <= lim);
            out[dst as usize] = [p[0] as f32, p[1] as f32, p[2] as f32];
        }
        return bad;
    }
    let out = SharedSlots(out.as_mut_ptr());
    rows.par_chunks(CHUNK)
        .zip(inv.par_chunks(CHUNK))
        .map(|(v, idx)| {
            let out = &out;
            let mut bad = false;
            for (p, &dst) in v.iter().zip(idx) {
                bad |= !(p[0].abs() <= lim && p[1].abs() <= lim && p[2].abs() <= lim);
                // SAFETY: `inv` is a permutation of 0..out.len(), so each slot is in bounds and
                // written by exactly one row: no two threads write the same slot.
                unsafe { *out.0.add(dst as usize) = [p[0] as f32, p[1] as f32, p[2] as f32] };
            }
            bad
        })
        .reduce(|| false, |a, b| a || b)
}

/// One polygon's state change at update `n` with silhouette edge `code` (or `NO_EDGE`).
struct Step {
    code: u8,
    s: usize,
    h: u32,
    n: u32,
}

impl Step {
    /// Writes the polygon's ring element for this update into `elem` and, at a birth, the
    /// element of the previous update into `prev_elem`.
    #[inline]
    fn apply(&self, fade: &mut u8, st: &mut Hot, elem: &mut u8, prev_elem: &mut u8) {
        let (code, s) = (self.code, self.s);
        let alive = (*fade as usize) < s;
        if code != NO_EDGE {
            if alive {
                *fade = fade.saturating_sub(1);
                st.run = (st.run as usize + 1).min(s) as u8;
            } else {
                *fade = 0;
                st.run = 2.min(s) as u8;
                *prev_elem = code;
            }
            st.last = code;
            st.last_on = self.n;
            *elem = code | ON_SILHOUETTE;
        } else if alive {
            let since = if st.last_on == NEVER {
                u32::MAX
            } else {
                self.n.wrapping_sub(st.last_on)
            };
            if since > self.h {
                *fade += 1;
            }
            if (*fade as usize) < s {
                st.run = (st.run as usize + 1).min(s) as u8;
                *elem = st.last;
            } else {
                st.run = 0;
            }
        }
    }
}
