//! A shell's history as bytes and back, so that a shell can be pickled, deep-copied or sent to
//! another process: everything [`BlurShell::new`] does not derive from its arguments (update
//! count, facing, snapshots, rings, per-polygon state), little-endian, behind a header that
//! names the shell's sizes. [`BlurShell::restore`] takes them into a shell made with the same
//! arguments, which then builds and updates exactly as the original would.
use super::blur_shell::{BlurShell, Hot, ON_SILHOUETTE};
use crate::contour::NO_EDGE;
use crate::error::{Error, Result};

const MAGIC: &[u8; 8] = b"MBSHELL1";

struct Reader<'a> {
    data: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if self.data.len() < n {
            return Err(Error::value("state", "is truncated"));
        }
        let (head, rest) = self.data.split_at(n);
        self.data = rest;
        Ok(head)
    }
    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f32s(&mut self, n: usize) -> Result<Vec<[f32; 3]>> {
        let raw = self.take(n.checked_mul(12).ok_or_else(too_big)?)?;
        Ok(raw
            .chunks_exact(12)
            .map(|c| {
                std::array::from_fn(|k| {
                    f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"))
                })
            })
            .collect())
    }
}

fn too_big() -> Error {
    Error::value("state", "has impossible sizes")
}

fn put_f32s(out: &mut Vec<u8>, rows: &[[f32; 3]]) {
    for r in rows {
        for x in r {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

impl BlurShell {
    /// The shell's history as bytes (see the module docs).
    pub fn history(&self) -> Vec<u8> {
        let s = self.opts.subdivisions as usize;
        let (nv, nf) = (self.n_vertices, self.faces.len());
        let mut out = Vec::with_capacity(64 + (s + 1) * nv * 24 + nv + nf * (12 + s + 7));
        out.extend_from_slice(MAGIC);
        for x in [nv, nf, s, self.updates as usize, self.spare] {
            out.extend_from_slice(&(x as u64).to_le_bytes());
        }
        for &b in &self.buf_of_slot {
            out.extend_from_slice(&(b as u64).to_le_bytes());
        }
        out.extend(self.facing.iter().map(|&f| f as u8));
        put_f32s(&mut out, &self.face_n);
        for b in self.pos_bufs.iter().chain(&self.nrm_bufs) {
            put_f32s(&mut out, b);
        }
        out.extend_from_slice(&self.ring);
        out.extend_from_slice(&(self.scratch_row.len() as u64).to_le_bytes());
        out.extend_from_slice(&self.scratch_row);
        out.extend_from_slice(&self.fade);
        for h in &self.hot {
            out.push(h.last);
            out.push(h.run);
            out.extend_from_slice(&h.last_on.to_le_bytes());
        }
        out
    }

    /// Takes the history `data` of a shell made with the same faces and options. Errors name
    /// `state` when the bytes are not such a history (other sizes, truncated, bad indices); the
    /// shell is unchanged then.
    pub fn restore(&mut self, data: &[u8]) -> Result<()> {
        let s = self.opts.subdivisions as usize;
        let (nv, nf) = (self.n_vertices, self.faces.len());
        let mut r = Reader { data };
        if r.take(MAGIC.len())? != MAGIC {
            return Err(Error::value("state", "is not a blur shell's history"));
        }
        let head: Vec<u64> = (0..5).map(|_| r.u64()).collect::<Result<_>>()?;
        if head[..3] != [nv as u64, nf as u64, s as u64] {
            return Err(Error::value(
                "state",
                format!(
                    "is the history of a shell of {} vertices, {} faces and {} subdivisions, \
                     not of this one ({nv}, {nf}, {s})",
                    head[0], head[1], head[2]
                ),
            ));
        }
        let (updates, spare) = (head[3], head[4] as usize);
        let buf_of_slot: Vec<usize> = (0..s)
            .map(|_| r.u64().map(|b| b as usize))
            .collect::<Result<_>>()?;
        let mut seen = vec![false; s + 1];
        for &b in buf_of_slot.iter().chain(std::iter::once(&spare)) {
            if b > s || seen[b] {
                return Err(Error::value("state", "has inconsistent snapshot buffers"));
            }
            seen[b] = true;
        }
        let facing: Vec<i8> = r.take(nv)?.iter().map(|&b| b as i8).collect();
        let face_n = r.f32s(nf)?;
        let mut bufs = Vec::with_capacity(2 * (s + 1));
        for _ in 0..2 * (s + 1) {
            bufs.push(r.f32s(nv)?);
        }
        let nrm_bufs = bufs.split_off(s + 1);
        let ring = r.take(s.checked_mul(nf).ok_or_else(too_big)?)?.to_vec();
        let scratch_len = r.u64()? as usize;
        if scratch_len != self.scratch_row.len() {
            return Err(Error::value("state", "has a scratch row of another size"));
        }
        let scratch_row = r.take(scratch_len)?.to_vec();
        let fade = r.take(nf)?.to_vec();
        let raw_hot = r.take(nf.checked_mul(6).ok_or_else(too_big)?)?;
        if !r.data.is_empty() {
            return Err(Error::value("state", "has trailing bytes"));
        }
        let code_ok = |c: &u8| c & !ON_SILHOUETTE <= NO_EDGE;
        let hot: Vec<Hot> = raw_hot
            .chunks_exact(6)
            .map(|c| Hot {
                last: c[0],
                run: c[1],
                last_on: u32::from_le_bytes(c[2..6].try_into().expect("4 bytes")),
            })
            .collect();
        if !ring.iter().chain(&scratch_row).all(code_ok)
            || hot.iter().any(|h| h.last > NO_EDGE || h.run as usize > s)
            || facing.iter().any(|f| !(-1..=1).contains(f))
        {
            return Err(Error::value(
                "state",
                "has out-of-range edge codes or facings",
            ));
        }
        self.updates = updates;
        self.spare = spare;
        self.buf_of_slot = buf_of_slot;
        self.facing = facing;
        self.face_n = face_n;
        self.pos_bufs = bufs;
        self.nrm_bufs = nrm_bufs;
        self.ring = ring;
        self.scratch_row = scratch_row;
        self.fade = fade;
        self.hot = hot;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ShellColor, ShellOptions};

    fn shell() -> BlurShell {
        let faces = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]];
        let opts = ShellOptions {
            subdivisions: 3,
            hysteresis: 1,
            initial_alpha: 1.0,
        };
        BlurShell::new(faces, 4, opts, None, ShellColor::Uniform([1.0; 4])).unwrap()
    }

    fn tetra(x: f64) -> Vec<[f64; 3]> {
        vec![
            [x, 0.0, 0.0],
            [x + 1.0, 0.0, 0.0],
            [x, 1.0, 0.0],
            [x, 0.0, 1.0],
        ]
    }

    #[test]
    fn a_restored_shell_goes_on_as_the_original() {
        let mut a = shell();
        for i in 0..5 {
            a.update(&tetra(0.3 * i as f64), None).unwrap();
        }
        let mut b = shell();
        b.restore(&a.history()).unwrap();
        assert_eq!(a.history(), b.history());
        for i in 5..9 {
            a.update(&tetra(0.25 * i as f64), None).unwrap();
            b.update(&tetra(0.25 * i as f64), None).unwrap();
        }
        assert_eq!(a.history(), b.history());
        assert_eq!(a.state(), b.state());
    }

    #[test]
    fn foreign_or_damaged_bytes_are_refused_and_change_nothing() {
        let mut a = shell();
        a.update(&tetra(0.0), None).unwrap();
        a.update(&tetra(0.5), None).unwrap();
        let h = a.history();
        let mut b = shell();
        let before = b.history();
        assert!(b.restore(&h[..h.len() - 1]).is_err());
        assert!(b.restore(&[h.clone(), vec![0]].concat()).is_err());
        assert!(b.restore(b"not a shell").is_err());
        let mut other = BlurShell::new(
            vec![[0, 1, 2]],
            3,
            ShellOptions::default(),
            None,
            ShellColor::Uniform([1.0; 4]),
        )
        .unwrap();
        assert!(other.restore(&h).is_err());
        assert_eq!(b.history(), before);
    }
}
