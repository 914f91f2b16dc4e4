use skg_core::scene::{Overrides, SceneFile};
use skg_core::model::Model;
use skg_core::solve::predict::{Candidate, Predictor};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut ov = Overrides::default();
    ov.nodes = Some(17);
    if args.len() > 3 { ov.verify_tol = Some(args[3].parse().unwrap()); }
    let scene = SceneFile::load(std::path::Path::new(&args[1])).unwrap().resolve(&ov).unwrap();
    let model = Model::build(&scene).unwrap();
    let t = std::time::Instant::now();
    let mut p = Predictor::new(&scene, &model).unwrap();
    println!("new {:.4} steps {:?}", t.elapsed().as_secs_f64(), p.steps);
    let ns: Vec<usize> = args[2].split(',').map(|s| s.parse().unwrap()).collect();
    for c in Candidate::all() {
        for &n in &ns {
            let t = std::time::Instant::now();
            let r = p.ratio(c, n).unwrap();
            println!("{} {} {:.3e} {:.4}", c.describe(), n, r, t.elapsed().as_secs_f64());
        }
    }
}
