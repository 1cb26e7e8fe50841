//! Every input a fuzz target (`fuzz/fuzz_targets/`) ever crashed on, kept under
//! `tests/fuzz_regressions/<target>/` and replayed here with the target's own check: the reader
//! returns an `Err`, or a mesh that passes `io::validate`.

use std::path::Path;

fn replay(target: &str, check: fn(&Path, &[u8])) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_regressions")
        .join(target);
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        check(&p, &std::fs::read(&p).unwrap());
        n += 1;
    }
    n
}

fn reader(parse: fn(&Path, &[u8]) -> scansurf::Result<scansurf::Mesh>) -> impl Fn(&Path, &[u8]) {
    move |p, bytes| {
        if let Ok(m) = parse(p, bytes) {
            if let Err(e) = scansurf::io::validate(p, &m) {
                panic!("{}: reader output fails validate: {e}", p.display());
            }
        }
    }
}

#[test]
fn readers_on_past_crashes() {
    use scansurf::io::{obj, ply, stl, xyz};
    let mut total = 0;
    total += replay("ply", |p, b| reader(ply::parse)(p, b));
    total += replay("obj", |p, b| reader(obj::parse)(p, b));
    total += replay("stl", |p, b| reader(stl::parse)(p, b));
    total += replay("xyz", |p, b| reader(xyz::parse)(p, b));
    assert!(total >= 1);
}

#[test]
fn overflowing_obj_normal_is_a_syntax_error() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_regressions/obj/overflowing_normal.obj");
    let e = scansurf::io::obj::parse(&p, &std::fs::read(&p).unwrap()).unwrap_err();
    assert!(e.to_string().contains("normal 1"), "{e}");
}
