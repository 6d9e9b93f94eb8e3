//! The order in which a sparse Cholesky factorization eliminates its unknowns: reverse
//! Cuthill-McKee on the graph of the unknowns (or blocks of them) that the matrix couples, which
//! keeps the factor's fill within the bandwidth of that order (a chain of bodies, such as a
//! prism's struts, keeps a band of one block). nalgebra-sparse's Cholesky eliminates in the
//! order it is given. The relaxation's sparse step and the projection order free bodies by it,
//! the large equilibrium matrix's null spaces their rows and columns (`structure/sparse_null.rs`).

/// The body (block) farthest from `start` by breadth-first search among the unvisited blocks:
/// a start at one end of the graph gives a narrow band.
fn farthest(neighbours: &[Vec<usize>], start: usize, visited: &[bool]) -> usize {
    let mut seen = visited.to_vec();
    let mut queue = std::collections::VecDeque::from([start]);
    seen[start] = true;
    let mut last = start;
    while let Some(i) = queue.pop_front() {
        last = i;
        for &k in &neighbours[i] {
            if !seen[k] {
                seen[k] = true;
                queue.push_back(k);
            }
        }
    }
    last
}

/// The factor position of each of the blocks coupled as `neighbours` (reverse Cuthill-McKee:
/// breadth first from a peripheral block, neighbours by increasing degree, then reversed).
pub(crate) fn reverse_cuthill_mckee(neighbours: &[Vec<usize>]) -> Vec<usize> {
    let n = neighbours.len();
    let degree = |i: usize| neighbours[i].len();
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    while order.len() < n {
        let least = (0..n).filter(|&i| !visited[i]).min_by_key(|&i| degree(i)).expect("a block is left");
        let start = farthest(neighbours, least, &visited);
        visited[start] = true;
        let mut head = order.len();
        order.push(start);
        while head < order.len() {
            let i = order[head];
            head += 1;
            let mut next: Vec<usize> = neighbours[i].iter().copied().filter(|&k| !visited[k]).collect();
            next.sort_by_key(|&k| (degree(k), k));
            next.dedup();
            for k in next {
                visited[k] = true;
                order.push(k);
            }
        }
    }
    let mut position = vec![0; n];
    for (p, &i) in order.iter().rev().enumerate() {
        position[i] = p;
    }
    position
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of 50 blocks numbered at random (and a separate pair) is ordered with a band
    /// of one: coupled blocks sit at most one position apart, and every position is used once.
    #[test]
    fn a_shuffled_chain_is_ordered_as_a_band() {
        let n = 52;
        let label = |i: usize| (i * 37) % n; // 37 is prime to 52: a permutation
        let mut neighbours = vec![Vec::new(); n];
        let mut couple = |a: usize, b: usize| {
            neighbours[label(a)].push(label(b));
            neighbours[label(b)].push(label(a));
        };
        for i in 0..49 {
            couple(i, i + 1);
        }
        couple(50, 51);
        let position = reverse_cuthill_mckee(&neighbours);
        let mut used = position.clone();
        used.sort_unstable();
        assert_eq!(used, (0..n).collect::<Vec<_>>());
        for (i, ks) in neighbours.iter().enumerate() {
            for &k in ks {
                assert!(position[i].abs_diff(position[k]) <= 1, "blocks {i} and {k}");
            }
        }
    }
}
