//! The inversion's small inputs: a lens plane, three image systems around an Einstein ring
//! of ~20 arcsec and six cluster members.

use glam::DVec2;
use wslap::{Cosmology, LensPlane};
use wslap::{Image, ImageCatalog, ImageSystem, Member, MemberCatalog};

pub fn plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).unwrap()
}

pub fn image(id: &str, x: f64, y: f64, a: f64, b: f64, theta: f64) -> Image {
    Image {
        id: id.to_string(),
        position: DVec2::new(x, y),
        a_arcsec: a,
        b_arcsec: b,
        theta_deg: theta,
        mag: 0.0,
        line: 1,
    }
}

pub fn system(id: &str, z: Option<f64>, images: Vec<Image>) -> ImageSystem {
    ImageSystem {
        id: id.to_string(),
        z,
        images,
    }
}

pub fn catalog(systems: Vec<ImageSystem>) -> ImageCatalog {
    ImageCatalog {
        source_name: "test.cat".to_string(),
        reference: None,
        systems,
    }
}

/// Three systems around an Einstein ring of ~20 arcsec, with ellipses.
pub fn three_systems() -> ImageCatalog {
    catalog(vec![
        system(
            "1",
            Some(2.0),
            vec![
                image("1.1", 18.0, 4.0, 1.0, 0.4, 10.0),
                image("1.2", -17.0, -6.0, 0.8, 0.5, 100.0),
                image("1.3", 3.0, 21.0, 0.6, 0.6, 0.0),
            ],
        ),
        system(
            "2",
            Some(3.5),
            vec![
                image("2.1", -5.0, 19.0, 1.2, 0.3, 45.0),
                image("2.2", 6.0, -20.0, 0.7, 0.4, -30.0),
            ],
        ),
        system(
            "3",
            Some(1.2),
            vec![
                image("3.1", 12.0, -12.0, 0.5, 0.5, 0.0),
                image("3.2", -14.0, 10.0, 0.5, 0.3, 80.0),
            ],
        ),
    ])
}

pub fn member(id: &str, x: f64, y: f64, mag: f64) -> Member {
    Member {
        id: id.to_string(),
        position: DVec2::new(x, y),
        a_arcsec: 1.0,
        b_arcsec: 1.0,
        theta_deg: 0.0,
        mag,
        lum: 1.0,
        line: 3,
    }
}

pub fn members() -> MemberCatalog {
    MemberCatalog {
        source_name: "members.cat".to_string(),
        reference: None,
        members: vec![
            member("a", 0.0, 0.0, 17.0),
            member("b", 10.0, 5.0, 19.5),
            member("c", -8.0, 12.0, 18.2),
            member("d", 15.0, -15.0, 20.1),
            member("e", -20.0, -3.0, 19.0),
            member("f", 3.0, -9.0, 18.9),
        ],
        commented: Vec::new(),
        fitted_bcgs: None,
        par_galaxies: Vec::new(),
        par_source: None,
        free_mass_galaxies: Vec::new(),
        mass_galaxies: Vec::new(),
    }
}
