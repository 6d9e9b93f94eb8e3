//! The equilibrium matrix of a pin-jointed structure and its four subspaces (Pellegrino and
//! Calladine, "Matrix analysis of statically and kinematically indeterminate frameworks",
//! Int. J. Solids Struct. 22(4), 1986).
//!
//! With the free nodes' coordinates stacked (3 j rows) and one column per member (b), the
//! equilibrium of the nodes under member tensions t and external loads f is A t = f: member
//! k's column holds, at each node of its path, the gradient of its length there (for a
//! two-node member between i and j, e_ij at i and -e_ij at j, e_ij the unit vector from i
//! to j), so that a tension pulls its nodes together. A's transpose is the compatibility
//! matrix: B = A^T maps node displacements d to member elongations e = A^T d. With r the
//! rank of A:
//! - s = b - r states of self-stress (A t = 0): tensions the structure holds without load;
//! - m = 3 j - r mechanisms (A^T d = 0): motions that stretch no member to first order, the
//!   rigid motions of a free structure among them;
//! - and Maxwell's rule as Calladine extended it, 3 j - b = m - s.
//!
//! The structure is pin-jointed where every free body is a point mass (a bead, an elastic
//! strut's end) or a strut's body (two nodes with the strut between them) and no joint holds
//! it: each node then has three coordinates, and every member, struts included, is a bar. A
//! node on a fixed body is a support in all three directions; a member between two supports
//! has no column. A support in some directions (`Structure::supports`) takes its held
//! coordinates out of the rows. Others are refused with the body that is not pin-jointed.

use super::{sparse_null, BodyKind, MemberId, NodeId, Structure, Vec3};
use nalgebra::{DMatrix, DVector};

/// Singular values below this fraction of the largest count as zero (the rank's tolerance):
/// far above the SVD's round-off (1e-16 of the largest), far below a genuine stiffness ratio
/// of a structure drawn to 1e-4 of its size.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// The most entries (3 j times b) the dense SVDs are given: 2.2e6 (a 300-strut prism, 1794 by
/// 1199: 6.5 s for both SVDs on one core; an SVD cannot be interrupted, so it is bounded).
/// Larger matrices go to the sparse null spaces (`sparse_null.rs`).
pub const MAX_EQUILIBRIUM_ENTRIES: usize = 2_200_000;

/// The most rows plus columns of the sparse analysis (a 1000-strut prism has 10,993).
pub const MAX_SPARSE_EQUILIBRIUM_SIZE: usize = 60_000;

/// The equilibrium matrix at a set of node positions and the subspaces of its SVD.
#[derive(Clone, Debug)]
pub struct EquilibriumMatrix {
    /// The free nodes.
    pub nodes: Vec<NodeId>,
    /// Each row's node and direction (0, 1, 2: x, y, z): the free nodes' coordinates that no
    /// support holds, node by node.
    pub rows: Vec<(NodeId, usize)>,
    /// The members, in the order of the columns.
    pub members: Vec<MemberId>,
    /// A's rows (3 j less the held coordinates) and columns (b).
    pub shape: (usize, usize),
    /// The singular values, largest first: every one from the dense SVD; from the sparse
    /// analysis (above [`MAX_EQUILIBRIUM_ENTRIES`]) the largest and the smallest nonzero.
    pub singular_values: Vec<f64>,
    /// Whether `singular_values` are all of them (the dense SVD).
    pub all_singular_values: bool,
    /// The rank r.
    pub rank: usize,
    /// The self-stress states (b each, orthonormal), s of them.
    pub self_stress: Vec<DVector<f64>>,
    /// m, the number of mechanisms.
    pub mechanism_count: usize,
    /// The mechanisms (one entry per row: node displacements, orthonormal): all m of them, but
    /// from the sparse analysis none where m is above [`sparse_null::MAX_BLOCK`] less its
    /// guard (a 1000-strut prism has 1996: only their count is given).
    pub mechanisms: Vec<DVector<f64>>,
}

/// Why a structure has no equilibrium matrix here.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{0}")]
pub struct EquilibriumError(pub String);

/// Whether `s` has an equilibrium matrix here: pin-jointed, and within
/// [`MAX_EQUILIBRIUM_ENTRIES`] (the check before a settle, without the matrix).
pub fn check(s: &Structure) -> Result<(), EquilibriumError> {
    layout(s).map(|_| ())
}

/// The free nodes, the rows (node, direction) and the columns' members of `s`'s equilibrium
/// matrix, once `s` is pin-jointed and the matrix within [`MAX_EQUILIBRIUM_ENTRIES`].
pub(super) type Layout = (Vec<NodeId>, Vec<(NodeId, usize)>, Vec<MemberId>);

fn layout(s: &Structure) -> Result<Layout, EquilibriumError> {
    check_pin_jointed(s)?;
    let free = |n: NodeId| s.bodies[s.nodes[n].body].kind == BodyKind::Free;
    let mut reached = vec![false; s.nodes.len()];
    for m in &s.members {
        m.path.iter().for_each(|&n| reached[n] = true);
    }
    let nodes: Vec<NodeId> = (0..s.nodes.len()).filter(|&n| free(n) && reached[n]).collect();
    let held = s.held_translations();
    let row_list: Vec<(NodeId, usize)> = nodes
        .iter()
        .flat_map(|&n| {
            let held = held[s.nodes[n].body];
            (0..3).filter(move |&x| !held[x]).map(move |x| (n, x))
        })
        .collect();
    let members: Vec<MemberId> = (0..s.members.len()).filter(|&k| s.members[k].path.iter().any(|&n| free(n))).collect();
    let (rows, columns) = (row_list.len(), members.len());
    if rows + columns > MAX_SPARSE_EQUILIBRIUM_SIZE {
        return Err(EquilibriumError(format!(
            "its equilibrium matrix would be {rows} by {columns}, more than the {MAX_SPARSE_EQUILIBRIUM_SIZE} rows and columns the sparse analysis is given here"
        )));
    }
    Ok((nodes, row_list, members))
}

/// The equilibrium matrix of `s` with its nodes at `positions` \[m\], and its SVD.
pub fn equilibrium_matrix(s: &Structure, positions: &[Vec3]) -> Result<EquilibriumMatrix, EquilibriumError> {
    let layout = layout(s)?;
    let dense = layout.1.len() * layout.2.len() <= MAX_EQUILIBRIUM_ENTRIES;
    analysis_of(s, positions, layout, dense)
}

/// [`equilibrium_matrix`] by the dense SVD (`dense`) or by the sparse null spaces
/// (`sparse_null.rs`), whatever the size (the two are checked against each other).
pub fn analysis(s: &Structure, positions: &[Vec3], dense: bool) -> Result<EquilibriumMatrix, EquilibriumError> {
    analysis_of(s, positions, layout(s)?, dense)
}

/// [`analysis`] of the `layout` of `s`.
fn analysis_of(
    s: &Structure,
    positions: &[Vec3],
    (nodes, rows, members): Layout,
    dense: bool,
) -> Result<EquilibriumMatrix, EquilibriumError> {
    let shape = (rows.len(), members.len());
    let (singular_values, self_stress, mechanisms) = if dense {
        let a = dense_matrix(s, positions, &rows, &members)?;
        let (singular_values, self_stress) = null_space(&a);
        (singular_values, self_stress, null_space(&a.transpose()).1)
    } else {
        let a = sparse_matrix(s, positions, &rows, &members)?;
        let stress = sparse_null::null_space(&a, &coupled(&a.transpose()))?;
        let m = shape.0 - (shape.1 - stress.basis.len());
        let motions = if m <= sparse_null::MAX_NULL {
            sparse_null::null_space(&a.transpose(), &coupled(&a))?.basis
        } else {
            Vec::new()
        };
        let values = [Some(stress.largest), stress.smallest_nonzero].into_iter().flatten().collect();
        (values, stress.basis, motions)
    };
    let rank = members.len() - self_stress.len();
    let (all_singular_values, mechanism_count) = (dense, shape.0 - rank);
    Ok(EquilibriumMatrix {
        nodes,
        rows,
        members,
        shape,
        singular_values,
        all_singular_values,
        rank,
        self_stress,
        mechanism_count,
        mechanisms,
    })
}

/// A as a sparse matrix (the same entries as [`matrix`]'s).
fn sparse_matrix(
    s: &Structure,
    positions: &[Vec3],
    rows: &[(NodeId, usize)],
    members: &[MemberId],
) -> Result<nalgebra_sparse::CscMatrix<f64>, EquilibriumError> {
    let mut coo = nalgebra_sparse::CooMatrix::new(rows.len(), members.len());
    entries(s, positions, rows, members, |r, c, x| coo.push(r, c, x))?;
    Ok(nalgebra_sparse::CscMatrix::from(&coo))
}

/// Each entry of A (row, column, value; repeated pairs add up): member k's column holds, at
/// each node of its path, minus the gradient of its length there.
fn entries(
    s: &Structure,
    positions: &[Vec3],
    rows: &[(NodeId, usize)],
    members: &[MemberId],
    mut entry: impl FnMut(usize, usize, f64),
) -> Result<(), EquilibriumError> {
    let row = row_index(s, rows);
    for (c, &k) in members.iter().enumerate() {
        for w in s.members[k].path.windows(2) {
            let (p, q) = (positions[w[0]], positions[w[1]]);
            let l = super::distance(p, q);
            if l <= 0.0 {
                return Err(EquilibriumError(format!("member '{}' has a segment of no length", s.members[k].name)));
            }
            for (node, sign) in [(w[0], 1.0), (w[1], -1.0)] {
                for x in 0..3 {
                    if let Some(r) = row[node][x] {
                        entry(r, c, sign * (q[x] - p[x]) / l);
                    }
                }
            }
        }
    }
    Ok(())
}

/// The columns of `a` that share a row, per column (the graph its Gram matrix couples). `at`
/// is A's transpose, whose columns are A's rows.
fn coupled(at: &nalgebra_sparse::CscMatrix<f64>) -> Vec<Vec<usize>> {
    let mut neighbours = vec![Vec::new(); at.nrows()];
    for column in at.col_iter() {
        let members = column.row_indices();
        for &i in members {
            neighbours[i].extend(members.iter().copied().filter(|&k| k != i));
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    neighbours
}

/// The layout of `s`'s equilibrium matrix and the matrix A with its nodes at `positions` \[m\],
/// dense: refused above [`MAX_EQUILIBRIUM_ENTRIES`] (the linear analysis too is dense).
pub(super) fn matrix(s: &Structure, positions: &[Vec3]) -> Result<(Layout, DMatrix<f64>), EquilibriumError> {
    let (nodes, rows, members) = layout(s)?;
    let a = dense_matrix(s, positions, &rows, &members)?;
    Ok(((nodes, rows, members), a))
}

/// A as a dense matrix, refused above [`MAX_EQUILIBRIUM_ENTRIES`].
fn dense_matrix(
    s: &Structure,
    positions: &[Vec3],
    rows: &[(NodeId, usize)],
    members: &[MemberId],
) -> Result<DMatrix<f64>, EquilibriumError> {
    if rows.len() * members.len() > MAX_EQUILIBRIUM_ENTRIES {
        return Err(EquilibriumError(format!(
            "its equilibrium matrix, {} by {}, is above the {MAX_EQUILIBRIUM_ENTRIES} entries a dense analysis is given here",
            rows.len(),
            members.len()
        )));
    }
    let mut a = DMatrix::zeros(rows.len(), members.len());
    entries(s, positions, rows, members, |r, c, x| a[(r, c)] += x)?;
    Ok(a)
}

/// Each node's row per direction (None: not a row: a fixed node's, or held by a support).
pub(super) fn row_index(s: &Structure, rows: &[(NodeId, usize)]) -> Vec<[Option<usize>; 3]> {
    let mut row = vec![[None; 3]; s.nodes.len()];
    for (k, &(n, x)) in rows.iter().enumerate() {
        row[n][x] = Some(k);
    }
    row
}

/// The displacement of each of the free `nodes` in the row vector `d` \[m\], zero along
/// their held directions (rows are listed node by node, in the order of `nodes`).
pub(super) fn displacements_by_node(
    nodes: &[NodeId],
    rows: &[(NodeId, usize)],
    d: &DVector<f64>,
) -> Vec<(NodeId, Vec3)> {
    let mut at: Vec<(NodeId, Vec3)> = nodes.iter().map(|&n| (n, [0.0; 3])).collect();
    let mut k = 0;
    for (r, &(n, x)) in rows.iter().enumerate() {
        while at[k].0 != n {
            k += 1;
        }
        at[k].1[x] = d[r];
    }
    at
}

impl EquilibriumMatrix {
    /// The displacement of each free node in the row vector `d` (a mechanism) \[m\], zero
    /// along its held directions, in the order of [`Self::nodes`].
    pub fn node_displacements(&self, d: &DVector<f64>) -> Vec<(NodeId, Vec3)> {
        displacements_by_node(&self.nodes, &self.rows, d)
    }
}

/// Every free body a point mass or a strut's two-node body, and no joint.
fn check_pin_jointed(s: &Structure) -> Result<(), EquilibriumError> {
    if let Some(j) = s.joints.first() {
        return Err(EquilibriumError(format!(
            "joint '{}' holds a body: the equilibrium matrix is that of a pin-jointed structure (free nodes and bars)",
            j.name
        )));
    }
    let points = super::lumped::point_masses(s);
    for (b, body) in s.bodies.iter().enumerate().filter(|(_, b)| b.kind == BodyKind::Free) {
        let own: Vec<NodeId> = (0..s.nodes.len()).filter(|&n| s.nodes[n].body == b).collect();
        let strut = own.len() == 2
            && s.members.iter().any(|m| m.is_rigid_strut() && m.path.contains(&own[0]) && m.path.contains(&own[1]));
        if !points[b] && !strut {
            return Err(EquilibriumError(format!(
                "body '{}' carries {} node(s) and is neither a point mass nor a strut's body: the equilibrium matrix is that of a pin-jointed structure (free nodes and bars)",
                body.name,
                own.len()
            )));
        }
    }
    Ok(())
}

/// The singular values of `m` (largest first) and an orthonormal basis of its null space:
/// the right singular vectors whose singular value is below [`RANK_TOLERANCE`] of the
/// largest, and those a wide matrix has beyond its rows (zero rows are added so that the SVD
/// gives every right singular vector).
fn null_space(m: &DMatrix<f64>) -> (Vec<f64>, Vec<DVector<f64>>) {
    let (rows, columns) = m.shape();
    if columns == 0 {
        return (Vec::new(), Vec::new());
    }
    let tall = if rows < columns { m.clone().resize_vertically(columns, 0.0) } else { m.clone() };
    let svd = tall.svd(false, true);
    let v_t = svd.v_t.expect("asked for");
    let mut order: Vec<usize> = (0..columns).collect();
    order.sort_by(|&i, &k| svd.singular_values[k].total_cmp(&svd.singular_values[i]));
    let largest = svd.singular_values.max();
    let values: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).take(rows.min(columns)).collect();
    let null = order
        .iter()
        .filter(|&&i| svd.singular_values[i] <= RANK_TOLERANCE * largest)
        .map(|&i| v_t.row(i).transpose())
        .collect();
    (values, null)
}
