//! Hold-out predictions (`wslap reconstruct --holdout`) on the teaching example (four
//! two-image systems behind one halo): quick, and every system has a redshift.

use glam::DVec2;
use wslap::app::examples::teaching_image_catalog;
use wslap::catalog::{parse_image_catalog, ImageCatalog};
use wslap::inversion::{ArcCatalog, ArcSystem, ConstraintMode, ConstraintSource};
use wslap::reconstruct::{reconstruct, ConvergenceRecord, Inputs, LayerSource, ReconstructConfig};
use wslap::solver::Control;
use wslap::{Cosmology, LensPlane};

fn quiet(_: &ConvergenceRecord) -> Control {
    Control::Continue
}

fn catalog() -> ImageCatalog {
    let text = teaching_image_catalog().unwrap();
    parse_image_catalog(&text, "images.cat", None).unwrap().0
}

/// The teaching example's settings, made quick: 16 x 16 cells, 300 iterations, 64-pixel maps.
fn config() -> ReconstructConfig {
    let mut c = ReconstructConfig::default();
    c.grid.cells = 16;
    c.solver.iterations = 300;
    c.products.pixels = 64;
    c.products.size_arcsec = Some(60.0);
    c
}

fn plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).unwrap()
}

fn ids(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Arc pixels instead of a catalogue: each image a 3 x 3 square of 0.2 arcsec pixels centred on
/// the catalogue position.
fn arcs_from(cat: &ImageCatalog) -> ArcCatalog {
    let square = |c: DVec2| -> Vec<DVec2> {
        (-1..=1)
            .flat_map(|i| (-1..=1).map(move |j| c + 0.2 * DVec2::new(i as f64, j as f64)))
            .collect()
    };
    ArcCatalog {
        source_name: "arcs.json".into(),
        systems: cat
            .systems
            .iter()
            .map(|s| ArcSystem {
                id: s.id.clone(),
                z: s.z,
                images: s.images.iter().map(|i| square(i.position)).collect(),
                image_ids: Vec::new(),
                line: 0,
            })
            .collect(),
    }
}

/// With arc pixels and no catalogue, a held-out system is predicted from its pixels: one
/// observed image per arc at the mean of its pixels (here the catalogue position), named
/// `system.k`, each with its nearest predicted image. Before, `--holdout` with `--arcs`
/// reported nothing for the held-out systems.
#[test]
fn held_out_arc_systems_are_predicted_from_their_pixels() {
    let cat = catalog();
    let arcs = arcs_from(&cat);
    let holdout = ids(&["2"]);
    let mut config = config();
    config.constraints.mode = ConstraintMode::Arcs;
    let inputs = Inputs {
        images: ConstraintSource::Arcs(&arcs),
        layers: LayerSource::None,
        plane: plane(),
        reference: cat.reference,
        holdout: &holdout,
        catalog: None,
    };
    let r = reconstruct(&inputs, &config, &mut quiet).unwrap();
    let held: Vec<_> = r.sources.iter().filter(|s| s.held_out).collect();
    assert_eq!(held.len(), 1);
    let (report, truth) = (held[0], &cat.systems[1]);
    assert_eq!(report.id, "2");
    assert_eq!(report.z, truth.z.unwrap());
    assert_eq!(report.observed.len(), truth.images.len());
    for (o, image) in report.observed.iter().zip(&truth.images) {
        assert_eq!(o.id, image.id);
        assert!(o.position_arcsec.distance(image.position) < 1e-12);
        let nearest = report
            .predicted
            .iter()
            .map(|p| p.position_arcsec.distance(o.position_arcsec))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(o.offset_arcsec, Some(nearest));
    }
    assert!(r.image_offset_median_arcsec(true).is_some());
}
