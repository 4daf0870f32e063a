//! The blur shell's internal vertex and face order, for cache-friendly per-update passes.
use crate::mesh::VertexFaces;

/// A cache-friendly internal order for the per-update passes: vertices renumbered in
/// breadth-first order over the mesh (neighbours get nearby numbers), faces sorted by their
/// lowest renumbered vertex. Positions are gathered into this order once per update, so the
/// face-normal and vertex-normal passes stream through memory whatever the caller's order.
/// Results do not depend on it: every vertex still sums its faces in original face order.
#[derive(Debug, Clone)]
pub struct Locality {
    /// Internal vertex `i` is the caller's vertex `perm[i]`.
    pub perm: Vec<u32>,
    /// The caller's vertex `v` is internal vertex `inv[v]`.
    pub inv: Vec<u32>,
    /// Faces in the caller's order, with internal vertex numbers.
    pub ifaces: Vec<[u32; 3]>,
    /// Faces in internal order (sorted by lowest internal vertex), with internal vertex numbers.
    pub bfaces: Vec<[u32; 3]>,
    /// Per internal vertex, its faces as indices into `bfaces`, in original face order.
    pub vf: VertexFaces,
}

impl Locality {
    /// The order of `faces` over `n_vertices` vertices.
    pub fn new(faces: &[[u32; 3]], n_vertices: usize) -> Self {
        let by_vertex = VertexFaces::new(faces, n_vertices);
        // Breadth-first order over vertices sharing a face; components in original order.
        let mut inv = vec![u32::MAX; n_vertices];
        let mut perm = Vec::with_capacity(n_vertices);
        let mut head = 0;
        for seed in 0..n_vertices {
            if inv[seed] != u32::MAX {
                continue;
            }
            inv[seed] = perm.len() as u32;
            perm.push(seed as u32);
            while head < perm.len() {
                let v = perm[head] as usize;
                head += 1;
                for &f in by_vertex.faces_of(v) {
                    for &w in &faces[f as usize] {
                        if inv[w as usize] == u32::MAX {
                            inv[w as usize] = perm.len() as u32;
                            perm.push(w);
                        }
                    }
                }
            }
        }
        let ifaces: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| [inv[f[0] as usize], inv[f[1] as usize], inv[f[2] as usize]])
            .collect();
        // Faces sorted (stably) by their lowest internal vertex: a counting sort.
        let mut start = vec![0u32; n_vertices + 1];
        for f in &ifaces {
            start[*f.iter().min().unwrap_or(&0) as usize + 1] += 1;
        }
        for i in 0..n_vertices {
            start[i + 1] += start[i];
        }
        let mut slot_of = vec![0u32; faces.len()];
        let mut bfaces = vec![[0u32; 3]; faces.len()];
        for (fi, f) in ifaces.iter().enumerate() {
            let s = &mut start[*f.iter().min().unwrap_or(&0) as usize];
            slot_of[fi] = *s;
            bfaces[*s as usize] = *f;
            *s += 1;
        }
        // Per internal vertex, its faces' internal slots, in original face order.
        let mut vf = VertexFaces::new(&ifaces, n_vertices);
        vf.rename_faces(|f| slot_of[f as usize]);
        Locality {
            perm,
            inv,
            ifaces,
            bfaces,
            vf,
        }
    }
}
