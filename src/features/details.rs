//! Small regions bounded by mild creases are surface detail, not faces: the horns of a coarse
//! organic mesh stand off its head at 38 degrees, a machined part's smallest faces (a bolt
//! hole's wall, a chamfer) meet their neighbours at 45 degrees or more. A region holding less
//! than `min_fraction` of all labelled elements whose creases to its neighbours are, by their
//! length-weighted mean, milder than `max_angle_deg` joins the neighbour it shares the longest
//! boundary with, smallest first, so that an organic scan shows no creases where a designer
//! would draw none.

use super::union_find::DisjointSets;
use super::RegionPair;

/// Absorbs the detail regions of a labelling (module doc). `label` holds a region per element
/// (faces of a mesh, points of a cloud; `u32::MAX` for none), `pairs` the regions meeting at a
/// crease with their dihedral angles and boundary sizes. Relabels in place, renumbers the
/// regions 0.. in order and returns their count and the pairs between them (dihedral of the
/// longest boundary, boundary sizes summed).
pub fn absorb_details(
    label: &mut [u32],
    regions: usize,
    pairs: &[RegionPair],
    min_fraction: f64,
    max_angle_deg: f64,
) -> (usize, Vec<RegionPair>) {
    let mut pairs = pairs.to_vec();
    let mut count = regions;
    loop {
        let mut size = vec![0usize; count];
        for &l in label.iter() {
            if (l as usize) < count {
                size[l as usize] += 1;
            }
        }
        let total: usize = size.iter().sum();
        let mild = |r: u32| {
            let (mut w, mut a) = (0.0, 0.0);
            for p in pairs.iter().filter(|p| p.a == r || p.b == r) {
                w += p.boundary_samples as f64;
                a += p.dihedral_deg * p.boundary_samples as f64;
            }
            w > 0.0 && a / w < max_angle_deg
        };
        let victim = (0..count as u32)
            .filter(|&r| (size[r as usize] as f64) < min_fraction * total as f64 && mild(r))
            .min_by_key(|&r| (size[r as usize], r));
        let Some(r) = victim else { break };
        let Some(into) = pairs
            .iter()
            .filter(|p| p.a == r || p.b == r)
            .max_by(|x, y| {
                x.boundary_samples
                    .cmp(&y.boundary_samples)
                    .then(y.a.cmp(&x.a))
            })
            .map(|p| if p.a == r { p.b } else { p.a })
        else {
            break;
        };
        let mut sets = DisjointSets::new(count);
        sets.union(r, into);
        let (map, c) = sets.labels();
        for l in label.iter_mut() {
            if (*l as usize) < count {
                *l = map[*l as usize];
            }
        }
        pairs = remap_pairs(&pairs, &map);
        count = c;
    }
    (count, pairs)
}

/// The region pairs after regions were relabelled by `map` (old region -> new): pairs within
/// one new region dropped, pairs that became one summed (boundary sizes added, the dihedral of
/// the longest boundary kept), sorted.
pub fn remap_pairs(pairs: &[RegionPair], map: &[u32]) -> Vec<RegionPair> {
    let mut merged: Vec<RegionPair> = Vec::new();
    for p in pairs {
        let (a, b) = (map[p.a as usize], map[p.b as usize]);
        if a == b {
            continue;
        }
        let (a, b) = (a.min(b), a.max(b));
        match merged.iter_mut().find(|q| q.a == a && q.b == b) {
            Some(q) => {
                if p.boundary_samples > q.boundary_samples {
                    q.dihedral_deg = p.dihedral_deg;
                }
                q.boundary_samples += p.boundary_samples;
            }
            None => merged.push(RegionPair { a, b, ..*p }),
        }
    }
    merged.sort_by_key(|p| (p.a, p.b));
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(a: u32, b: u32, deg: f64, n: usize) -> RegionPair {
        RegionPair {
            a,
            b,
            dihedral_deg: deg,
            boundary_samples: n,
        }
    }

    #[test]
    fn a_small_mild_region_joins_its_neighbour_and_a_small_sharp_one_stays() {
        // Region 0: 1,000 elements; 1: 5 elements at 38 degrees; 2: 5 elements at 90 degrees.
        let mut label: Vec<u32> = std::iter::repeat_n(0, 1000)
            .chain(std::iter::repeat_n(1, 5))
            .chain(std::iter::repeat_n(2, 5))
            .collect();
        let pairs = [pair(0, 1, 38.0, 10), pair(0, 2, 90.0, 10)];
        let (count, pairs) = absorb_details(&mut label, 3, &pairs, 0.01, 45.0);
        assert_eq!(count, 2);
        assert_eq!(label[1002], 0);
        assert_eq!(label[1007], 1);
        assert_eq!(pairs.len(), 1);
        assert_eq!(
            (pairs[0].a, pairs[0].b, pairs[0].dihedral_deg),
            (0, 1, 90.0)
        );
        // A large region stays whatever its angle.
        let mut label: Vec<u32> = std::iter::repeat_n(0, 100)
            .chain(std::iter::repeat_n(1, 50))
            .collect();
        let (count, _) = absorb_details(&mut label, 2, &[pair(0, 1, 25.0, 9)], 0.01, 45.0);
        assert_eq!(count, 2);
    }
}
