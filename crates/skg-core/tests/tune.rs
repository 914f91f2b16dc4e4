//! The automatic choice of a wall width ([`skg_core::tune`]) against the paper's.

mod common;

use skg_core::scene::{Overrides, SceneFile};
use skg_core::tune::{self, TuneOptions};

#[test]
fn sigma_auto_selection_reproduces_the_papers_choice() {
    // Tumbler at N = 256: artifacts appear between sigma = 1/120 and 1/110 (docs/solver.md),
    // so the smallest artifact-free width at the default tolerance lies in between.
    let file = SceneFile::load(&common::scenario("tumbler")).unwrap();
    let opts = TuneOptions { lo: Some(1.0 / 160.0), hi: Some(1.0 / 90.0), rel: 0.03, ..TuneOptions::default() };
    let mut seen = 0;
    let r = tune::tune_width(&file, &Overrides::default(), &opts, |_| seen += 1).unwrap();
    assert_eq!(r.param, "sigma");
    assert_eq!(seen, r.steps.len());
    assert!(r.chosen > 1.0 / 120.0 && r.chosen <= 1.0 / 108.0, "chosen 1/{:.1}", 1.0 / r.chosen);
    let failing = r.failing.unwrap();
    assert!(r.chosen / failing < 1.0 + opts.rel + 1e-12);
    // Every step is consistent with the choice (monotone artifact).
    for s in &r.steps {
        assert_eq!(s.ok, s.value >= r.chosen, "{s:?}");
    }
}
