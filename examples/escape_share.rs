//! Prints the ray escape share of `scansurf::openings::enclosure` for each input given
//! (the measurement behind `fit --close auto`'s threshold).
fn main() {
    for path in std::env::args().skip(1) {
        let mesh = match scansurf::io::read_mesh(std::path::Path::new(&path)) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        let op = match scansurf::normals::oriented_points(&mesh, 12) {
            Ok(o) => o,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        let t = std::time::Instant::now();
        let e = scansurf::openings::enclosure::escape_share(&op.points, &op.normals);
        println!(
            "{path}: escape share {:.4} ({} of {} rays), {:.3} s",
            e.escape_share,
            e.escaped,
            e.rays,
            t.elapsed().as_secs_f64()
        );
    }
}
