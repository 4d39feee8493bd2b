//! Lenstool `.par` files of the shapes published models have (tests/data/lenstool/, each a
//! small file written after a public one, see its README.md): each loads as Lenstool loads it,
//! or says precisely (file, line, block, value) why not.

use glam::DVec2;
use wslap::{parse_image_catalog, ParComponent, Radius, RedshiftPrior};
use wslap::{parse_par, parse_par_with, Dpie, LensPlane, MassComponent, ParOptions};

/// `data.add_par_galaxies(par)` with the default member law on the `.par`'s lens plane: its
/// notes.
fn add_galaxies(data: &mut wslap::Dataset, par: &wslap::LenstoolPar) -> Vec<String> {
    data.add_par_galaxies(par, &par.lens_plane().unwrap(), &Default::default())
        .unwrap()
}

const SINGULAR_CORE: &str = include_str!("../data/lenstool/singular_core.par");
const MEMBERS: &str = include_str!("../data/lenstool/members.cat");
const STRAY_END: &str = include_str!("../data/lenstool/stray_end.par");
const MULTIPLANE: &str = include_str!("../data/lenstool/multiplane.par");
const GROUP: &str = include_str!("../data/lenstool/group.cat");
const IDENTITY: &str = include_str!("../data/lenstool/identity.par");
const HPC_STYLE: &str = include_str!("../data/lenstool/hpc_style.par");
const PROFILE_8: &str = include_str!("../data/lenstool/profile_8.par");
const ENGLISH: &str = include_str!("../data/lenstool/english_bestopt.par");

fn refused(text: &str, name: &str) -> String {
    parse_par(text, name)
        .expect_err("must be refused")
        .to_string()
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn singular_cores_load_and_no_measurement_members_are_skipped() {
    let par = parse_par(SINGULAR_CORE, "singular_core.par").expect("loads");
    assert!(par.warnings.is_empty(), "{:?}", par.warnings);
    let ParComponent::Dpie { r_core, .. } = par.potentials[0].component else {
        panic!("O1 is a dPIE");
    };
    assert_eq!(r_core, Radius::Arcsec(0.0));
    assert_eq!(par.potfiles[0].r_core, Radius::Kpc(0.0));
    let (model, warnings) = par
        .build_from_texts(&[("members.cat", MEMBERS)])
        .expect("builds");
    // Rows 4 and 5 (magnitudes 99.000 and -99) say "no measurement": skipped, with a warning.
    assert_eq!((model.potentials, model.members), (1, 3));
    let lines: Vec<usize> = warnings.iter().map(|w| w.line).collect();
    assert_eq!(lines, [4, 5], "{warnings:?}");
    for (w, mag) in warnings.iter().zip(["99.000", "-99"]) {
        let text = w.to_string();
        assert!(
            text.starts_with("members.cat: line")
                && text.contains(mag)
                && text.contains("no measurement"),
            "{text}"
        );
    }
    // A dPIE of `v_disp 0` (a node of a Lenstool non-parametric grid, which starts at zero
    // mass) is massless: left out, the same lens.
    let node = "potentiel 0\n\tprofil 81\n\tx_centre 5.0\n\ty_centre 5.0\n\tellipticite 0\n\
                \tangle_pos 0\n\tcore_radius_kpc 10\n\tcut_radius_kpc 100\n\tv_disp 0.0\n\
                \tz_lens 0.3080\n\tend\npotfile0\n";
    let with_node = SINGULAR_CORE.replacen("potfile0\n", node, 1);
    assert_ne!(with_node, SINGULAR_CORE);
    let (same, _) = parse_par(&with_node, "node.par")
        .expect("loads")
        .build_from_texts(&[("members.cat", MEMBERS)])
        .expect("builds");
    assert_eq!((same.potentials, same.members), (1, 3));
    let at = glam::DVec2::new(3.0, -7.0);
    assert_eq!(same.lens.deflection(at), model.lens.deflection(at));
    // The build's error when the potfile's mag0 is `mag0` instead of 19.44: it must name the
    // member catalogue, the value and the band.
    let refused_with_mag0 = |mag0: &str| {
        let text = SINGULAR_CORE.replace("mag0    19.440000", &format!("mag0    {mag0}"));
        assert_ne!(text, SINGULAR_CORE);
        let e = parse_par(&text, "singular_core.par")
            .expect("loads")
            .build_from_texts(&[("members.cat", MEMBERS)])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("members.cat:")
                && e.contains(&format!("mag0 = {mag0}"))
                && e.contains("same band"),
            "{e}"
        );
    };
    // An L* magnitude in another band than the catalogue's (here off by 100 magnitudes)
    // scales the members far beyond any galaxy: the potfile's mag0 is named with the row.
    refused_with_mag0("119.44");
    // The other way (mag0 far brighter than every member) the members would be all but
    // massless, a map without its galaxies and no word of it: refused the same way.
    refused_with_mag0("-300");
    // A catalogue of no-measurement rows only has no member to use, and says so.
    let only_99: String = MEMBERS
        .lines()
        .filter(|l| !l.contains(" 1.0") || l.contains("99"))
        .map(|l| format!("{l}\n"))
        .collect();
    let e = wslap::parse_member_catalog(&only_99, "m.cat", None)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("m.cat: all 2 member row(s)") && e.contains("no-measurement"),
        "{e}"
    );
    // The singular halo and the singular members are finite everywhere, their centres too.
    let o1 = DVec2::new(-2.076312, 1.388524);
    for p in [
        o1,
        DVec2::new(10.0, -5.0),
        DVec2::new(0.0, 0.0),
        o1 + DVec2::X,
    ] {
        let (a, h) = model.lens.deflection_hessian(p);
        let k = model.lens.kappa(p);
        assert!(
            a.is_finite() && k.is_finite() && h.iter().all(|v| v.is_finite()),
            "{p}"
        );
    }
    // Away from the centres the halo is the a = 0 dPIE of its parameters.
    let halo = Dpie::new(
        o1,
        907.070068,
        0.0,
        1000.0 / kpc_per_arcsec(&model.plane),
        0.528247,
        90.533509,
    )
    .unwrap();
    let p = o1 + DVec2::new(30.0, 20.0);
    let members: DVec2 = model.lens.deflection(p) - halo.deflection(p);
    assert!(
        members.length() < 0.1 * halo.deflection(p).length(),
        "{members}"
    );
}

fn kpc_per_arcsec(plane: &LensPlane) -> f64 {
    1.0e3 * plane.mpc_per_arcsec
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_stray_end_before_fini_is_skipped_as_by_lenstool() {
    let par = parse_par(STRAY_END, "stray_end.par").expect("loads");
    assert_eq!((par.potentials.len(), par.potfiles.len()), (2, 1));
    assert!(par.warnings.is_empty(), "{:?}", par.warnings);
    // DOS line ends (Lenstool drops the CR) read the same.
    let crlf = parse_par(&STRAY_END.replace('\n', "\r\n"), "stray_end.par").expect("CRLF");
    assert_eq!(crlf.potentials, par.potentials);
    // A stray `end` between blocks, or two, anywhere.
    let text = STRAY_END.replace("potentiel O2\n", "\tend\nend\npotentiel O2\n");
    let again = parse_par(&text, "x.par").unwrap();
    let (a, b) = (&again.potentials, &par.potentials);
    assert!(a.len() == 2 && a.iter().zip(b).all(|(a, b)| a.component == b.component));
    // A fitted model's statistics above its blocks (A1689's best model of Limousin et al.,
    // every published bestopt.par) are skipped without a word, and the blocks after them read
    // as without.
    let text = format!("Chi2formey: 0.000\nChi2l: 0.000\nlog(Evidence) : -291.035\n{STRAY_END}");
    let headed = parse_par(&text, "headed.par").unwrap();
    let (h, b) = (&headed.potentials, &par.potentials);
    assert!(h.len() == 2 && h.iter().zip(b).all(|(h, b)| h.component == b.component));
    assert_eq!(headed.reference, par.reference);
    assert!(headed.warnings.is_empty(), "{:?}", headed.warnings);
    // Any other word there is still skipped with a warning, statistics after it or not.
    let text = format!("Chi2tot: 1.0\nnotes by hand\nChi2l: 0.000\n{STRAY_END}");
    let stray = parse_par(&text, "stray.par").unwrap();
    assert_eq!(stray.potentials.len(), 2);
    let [w] = &stray.warnings[..] else {
        panic!("{:?}", stray.warnings)
    };
    assert_eq!(w.line, 2);
    assert_eq!(
        w.message,
        "`notes` is not a Lenstool block: skipped, with the lines after it, up to the next \
         block or `end` (Lenstool skips it too)"
    );
    // Without its `end`, the block that is still open is named.
    let e = refused(&STRAY_END.replace("\tend\n\tend\nfini\n", ""), "cut.par");
    assert!(
        e.contains("cut.par:") && e.contains("`champ` has no `end`"),
        "{e}"
    );
}

/// The galaxies a `.par` models on its own are read from a model with a group at another
/// redshift (A370's CATS model has one at z = 1.05, and `wslap reconstruct --par` refused it):
/// the cluster's galaxies are fitted, a galaxy at the other redshift is named and not.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_galaxies_of_a_multi_plane_model_are_the_cluster_planes() {
    let options = ParOptions::default().for_galaxies();
    let par = parse_par_with(MULTIPLANE, "multiplane.par", &options).expect("read");
    let found = par.galaxies().unwrap();
    let ids: Vec<&str> = found.members.iter().map(|m| m.id.as_str()).collect();
    assert_eq!(ids, ["O2"]);
    assert!(found.other_plane.is_empty() && found.without_mag.is_empty());
    // The background potfile moved to one plane to be read is marked, so that a
    // reconstruction can say that it does not use it; the other warnings are not.
    let moved: Vec<(usize, Option<&str>)> = par
        .warnings
        .iter()
        .map(|w| (w.line, w.moved_block.as_deref()))
        .filter(|(_, b)| b.is_some())
        .collect();
    assert_eq!(moved, [(42, Some("potfile1"))]);
    // A galaxy of the background group modelled on its own (core 0.2 kpc, a `mag`).
    let background = "potentiel O3\n\tprofil       81\n\tx_centre     30.0\n\ty_centre     \
                      -20.0\n\tellipticite     0.1\n\tangle_pos       10.0\n\t\
                      core_radius_kpc     0.2\n\tcut_radius_kpc     20.0\n\tv_disp     \
                      150.0\n\tmag\t\t  20.5\n\tz_lens     1.0500\n\tend\npotfile0\n";
    let text = MULTIPLANE.replacen("potfile0\n", background, 1);
    let line = 1 + text[..text.find("potentiel O3").unwrap()]
        .matches('\n')
        .count();
    let par = parse_par_with(&text, "group.par", &options).expect("read");
    let found = par.galaxies().unwrap();
    assert_eq!(found.members.len(), 1);
    assert_eq!(
        found.other_plane,
        [("potentiel O3".to_string(), line, 1.05)]
    );
    let mut data = wslap::Dataset::default();
    let notes = add_galaxies(&mut data, &par);
    let expected = format!(
        "group.par: line {line}: `potentiel O3` is a galaxy at z = 1.05, not at the \
         cluster's z_lens = 0.375: not fitted"
    );
    assert!(notes.contains(&expected), "{notes:?}");
    assert_eq!(data.members.unwrap().members.len(), 1);
}

/// The `z_m_limit` lines of a `.par`'s `image` block (as the CATS and Jauzac et al. models
/// write them: `n id flag value1 value2 precision`) are the priors a reconstruction takes for
/// the systems they name: flag 0 fixed (a `best.par`'s fitted value), 1 uniform, 3 normal (a
/// `bestopt.par`'s posterior). A line that is none of these is skipped with a warning naming
/// it; an id is matched as a number (`14.0` is system 14) or as an image's (`A3a` of system
/// `A3`); several ids before the flag (as Lenstool's output files write families of one
/// source) each take the prior; an id no catalogue has is named, and a prior in front of the
/// lens (an optimiser at its floor, as in a public `best.par`) is not taken.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_par_s_redshift_priors_are_taken_for_the_systems_they_name() {
    let image = "image\n\tmultfile 1 mul.cat\n\tforme -2\n\
                 \tz_m_limit 1 6 1 2.0 3.0 0.1\n\
                 \tz_m_limit 2 14.0 3 2.842 0.403 0.0100\n\
                 \tz_m_limit 3 8.0 0 2.888 0.000 0.0000\n\
                 \tz_m_limit 4 9 2 1.0 2.0 0.1\n\
                 \tz_m_limit 5 10 1 3.0\n\
                 \tz_m_limit 6 11 1 3.0 2.0 0.1\n\
                 \tz_m_limit 7 99 1 1.0 2.0 0.1\n\
                 \tz_m_limit 8 A3a A4a 3 1.509576 0.038857 0.0010\n\
                 \tz_m_limit 9 16.0 0 0.100000  0.000000  0.0000\n\tend\n";
    let text = MULTIPLANE.replacen("potentiel O1\n", &format!("{image}potentiel O1\n"), 1);
    let line_of = |needle: &str| 1 + text[..text.find(needle).unwrap()].matches('\n').count();
    let options = ParOptions::default().for_galaxies();
    let par = parse_par_with(&text, "priors.par", &options).expect("read");
    let got: Vec<(usize, &str, RedshiftPrior)> = par
        .redshift_priors
        .iter()
        .map(|p| (p.line, p.system.as_str(), p.prior))
        .collect();
    assert_eq!(
        got,
        [
            (
                line_of("z_m_limit 1 "),
                "6",
                RedshiftPrior::Range([2.0, 3.0])
            ),
            (
                line_of("z_m_limit 2 "),
                "14.0",
                RedshiftPrior::Normal([2.842, 0.403])
            ),
            (line_of("z_m_limit 3 "), "8.0", RedshiftPrior::Fixed(2.888)),
            (
                line_of("z_m_limit 7 "),
                "99",
                RedshiftPrior::Range([1.0, 2.0])
            ),
            (
                line_of("z_m_limit 8 "),
                "A3a",
                RedshiftPrior::Normal([1.509576, 0.038857])
            ),
            (
                line_of("z_m_limit 8 "),
                "A4a",
                RedshiftPrior::Normal([1.509576, 0.038857])
            ),
            (line_of("z_m_limit 9 "), "16.0", RedshiftPrior::Fixed(0.1)),
        ]
    );
    let warnings: Vec<String> = par.warnings.iter().map(ToString::to_string).collect();
    for (n, why) in [
        ("4", "of system 9: flag `2` is not read here"),
        ("5", "needs `n id flag value1 value2`"),
        (
            "6",
            "of system 11: flag 1 with values 3 and 2 is not a redshift prior",
        ),
    ] {
        let head = format!(
            "priors.par:{}: `z_m_limit` {why}",
            line_of(&format!("z_m_limit {n} "))
        );
        assert!(
            warnings
                .iter()
                .any(|w| w.starts_with(&head) && w.ends_with(": skipped")),
            "{head}: {warnings:?}"
        );
    }
    let catalogue = "#REFERENCE 3 39.971340 -1.582260\n\
                     6.1 10.0 5.0 0.5 0.5 0 0 25\n6.2 -8.0 3.0 0.5 0.5 0 0 25\n\
                     8.1 4.0 -9.0 0.5 0.5 0 2.5 25\n8.2 -4.0 9.0 0.5 0.5 0 2.5 25\n\
                     14.1 20.0 1.0 0.5 0.5 0 0 25\n14.2 -19.0 2.0 0.5 0.5 0 0 25\n\
                     A3a 1.0 12.0 0.5 0.5 0 0 25\nA3b -1.0 -12.0 0.5 0.5 0 0 25\n\
                     A4a 2.0 12.0 0.5 0.5 0 0 25\nA4b -2.0 -12.0 0.5 0.5 0 0 25\n\
                     16.1 7.0 7.0 0.5 0.5 0 3.0 25\n16.2 -7.0 -7.0 0.5 0.5 0 3.0 25\n";
    let (images, _) = parse_image_catalog(catalogue, "mul.cat", None).unwrap();
    let mut data = wslap::Dataset {
        images: Some(images),
        ..Default::default()
    };
    let notes = data.add_par_redshift_priors(&par);
    assert_eq!(
        notes,
        [
            format!(
                "priors.par: line {}: system 6's redshift is estimated under the model's prior, \
                 uniform 2 - 3",
                line_of("z_m_limit 1 ")
            ),
            format!(
                "priors.par: line {}: system 14's redshift is estimated under the model's \
                 prior, normal 2.842 +- 0.403",
                line_of("z_m_limit 2 ")
            ),
            format!(
                "priors.par: line {}: system 8's redshift is taken as 2.888",
                line_of("z_m_limit 3 ")
            ),
            format!(
                "priors.par: line {}: `z_m_limit` names system 99, which no catalogue loaded \
                 has: not used",
                line_of("z_m_limit 7 ")
            ),
            format!(
                "priors.par: line {}: system A3's redshift is estimated under the model's \
                 prior, normal 1.509576 +- 0.038857",
                line_of("z_m_limit 8 ")
            ),
            format!(
                "priors.par: line {}: system A4's redshift is estimated under the model's \
                 prior, normal 1.509576 +- 0.038857",
                line_of("z_m_limit 8 ")
            ),
            format!(
                "priors.par: line {}: system 16's prior (fixed at 0.1) puts it in front of the \
                 lens (z_lens = 0.375): not used",
                line_of("z_m_limit 9 ")
            ),
        ]
    );
    let ids: Vec<&str> = data.z_priors.keys().map(String::as_str).collect();
    assert_eq!(ids, ["14", "6", "8", "A3", "A4"]);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_background_group_is_refused_or_moved_by_the_single_plane_option() {
    let e = refused(MULTIPLANE, "multiplane.par");
    for part in [
        "multiplane.par:42",
        "`potfile1`",
        "z_lens = 1.05",
        "0.375",
        "multi-plane",
        "--single-plane",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
    let options = ParOptions { single_plane: true };
    let par = parse_par_with(MULTIPLANE, "multiplane.par", &options).expect("single plane");
    assert_eq!(par.z_lens, 0.375);
    assert_eq!(par.warnings.len(), 1, "{:?}", par.warnings);
    let w = par.warnings[0].to_string();
    assert!(
        w.starts_with("multiplane.par:42:") && w.contains("`potfile1`") && w.contains("1.05"),
        "{w}"
    );
    // The group keeps its angular sizes: its kpc radii are converted on its own plane.
    let own = LensPlane::new(par.cosmology, 1.05).unwrap();
    let Radius::Arcsec(core) = par.potfiles[1].r_core else {
        panic!("converted to arcsec");
    };
    assert!((core - 0.15 / kpc_per_arcsec(&own)).abs() < 1e-15, "{core}");
    assert_eq!(par.potfiles[0].r_core, Radius::Kpc(0.15));
    let (model, _) = par
        .build_from_texts(&[("members.cat", MEMBERS), ("group.cat", GROUP)])
        .expect("builds");
    assert_eq!((model.potentials, model.members), (2, 3 + 2));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn keywords_lenstool_does_not_read_are_ignored_with_a_warning() {
    let par = parse_par(IDENTITY, "identity.par").expect("loads");
    assert_eq!(par.warnings.len(), 1, "{:?}", par.warnings);
    let w = par.warnings[0].to_string();
    assert!(
        w.starts_with("identity.par:26:") && w.contains("`identity`"),
        "{w}"
    );
    let r = par.reference.expect("reference from a long runmode");
    assert_eq!((r.ra_deg, r.dec_deg), (3.586259, -30.400174));
    assert_eq!(
        par.potentials[0].component,
        ParComponent::Dpie {
            center_arcsec: DVec2::new(-2.076312, 1.388524),
            sigma_v_km_s: 607.070068,
            r_core: Radius::Arcsec(18.816964),
            r_cut: Radius::Arcsec(221.244725),
            ellipticity: 0.828247,
            pa_deg: 90.533509,
        }
    );
    // A keyword Lenstool reads but the reader does not implement is still refused.
    let e = refused(
        &IDENTITY.replace(" \t identity O1\n", " \t rc_slope 0.5\n"),
        "x.par",
    );
    assert!(e.contains("x.par:26") && e.contains("`rc_slope`"), "{e}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn lenstool_hpc_inputs_say_what_lenstool_would_not_read() {
    // English names, a `frame` block, comments after values and `finish` are read; `rcut` and
    // `rcore` are not Lenstool keywords, so the dPIE has no cut radius.
    let e = refused(HPC_STYLE, "hpc_style.par");
    for part in [
        "hpc_style.par:21",
        "`potential 1`",
        "cut_radius",
        "`rcut`, `rcore`",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
    let fixed = HPC_STYLE
        .replace("\trcut\t500", "\tcut_radius\t500")
        .replace("\trcore \t5", "\tcore_radius \t5");
    let par = parse_par(&fixed, "hpc_style.par").expect("loads with Lenstool's keywords");
    assert_eq!(par.z_lens, 0.4);
    assert_eq!(par.warnings.len(), 1, "{:?}", par.warnings);
    let w = par.warnings[0].to_string();
    assert!(
        w.starts_with("hpc_style.par:6:") && w.contains("`frame`"),
        "{w}"
    );
    let ParComponent::Dpie {
        r_cut, ellipticity, ..
    } = par.potentials[0].component
    else {
        panic!("a dPIE");
    };
    assert_eq!((r_cut, ellipticity), (Radius::Arcsec(500.0), 0.11));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_recent_english_bestopt_loads_without_warnings() {
    let par = parse_par(ENGLISH, "english_bestopt.par").expect("loads");
    assert!(par.warnings.is_empty(), "{:?}", par.warnings);
    assert_eq!((par.potentials.len(), par.z_lens), (2, 0.588));
    assert_eq!(par.potentials[1].block, "potential O2");
    let r = par.reference.expect("reference");
    assert_eq!((r.ra_deg, r.dec_deg), (35.282193, -66.387198));
    let ParComponent::Dpie { ellipticity, .. } = par.potentials[0].component else {
        panic!("a dPIE");
    };
    assert_eq!(ellipticity, 0.600442);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_cosmology_or_radius_is_blamed_on_the_line_that_holds_it() {
    // identity.par's block: H0 70.0 on line 35, omegaM 0.3 on 36, omegaX 0.7 on 37; O1's
    // core radius on line 20.
    for (from, to, line, words) in [
        (
            "omegaM 0.3",
            "omegaM 1.3",
            36,
            "`omegaM` in block `cosmologie`: the matter density",
        ),
        (
            "omegaM 0.3",
            "omegaM -0.3",
            36,
            "must be 0 to 1 (got `-0.3`)",
        ),
        (
            "H0 70.0",
            "H0 0",
            35,
            "`H0` in block `cosmologie`: H0 must be above 0",
        ),
        (
            "omegaM 0.3",
            "omegaM 0.03",
            37,
            "omegaM + omegaX must be 1 (got `0.7`)",
        ),
        // A negative radius is refused as written (kpc or arcsec), not once converted.
        (
            "core_radius 18.816964",
            "core_radius_kpc -5",
            20,
            "`core_radius_kpc` in block `potentiel O1`: a radius must be 0 or more (got `-5`)",
        ),
    ] {
        let text = IDENTITY.replace(from, to);
        assert_ne!(text, IDENTITY, "{from}");
        let e = refused(&text, "cosmo.par");
        assert!(
            e.starts_with(&format!("cosmo.par:{line}: ")) && e.contains(words),
            "{to}: {e}"
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn profiles_other_than_dpie_and_shear_are_named() {
    let e = refused(PROFILE_8, "profile_8.par");
    assert!(
        e.contains("profile_8.par:9") && e.contains("`potentiel 1`") && e.contains("profil 8"),
        "{e}"
    );
}

/// HFF-style deflection maps with NaN and zero borders and one NaN pixel inside
/// (tests/data/hff_borders_reference.py: an SIS of theta_E = 6 arcsec, 40 x 40 pixels of 0.5
/// arcsec): the pixels without data are found, left blank (NaN) in every map and FITS file,
/// and the curves and the profile use the rest.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn hff_maps_with_blank_and_zero_borders_are_used_without_them() {
    use wslap::{read_image, Cosmology, LensPlane, NoDataPixels, Products};
    let read = |bytes: &[u8], name: &str| {
        let image = read_image(bytes, name).unwrap();
        let (_, reference) = image.geometry().unwrap();
        let (map, no_data) = image.to_map_no_data().unwrap();
        (map, no_data, reference)
    };
    let (ax, nx, reference) = read(
        include_bytes!("../data/hff_borders_x-arcsec-deflect.fits"),
        "x.fits",
    );
    let (ay, ny, _) = read(
        include_bytes!("../data/hff_borders_y-arcsec-deflect.fits"),
        "y.fits",
    );
    // NaN: 3 East columns and 2 North rows (less the West zeros) and one pixel; zeros: 3 South
    // rows and 4 West columns.
    let expected = NoDataPixels {
        blank: 3 * 35 + 2 * 36 + 1,
        zero_border: 3 * 40 + 4 * 37,
    };
    assert_eq!((nx, ny), (expected, expected));
    assert!(ax.at(2, 20).is_nan() && ax.at(37, 20).is_nan() && ax.at(20, 1).is_nan());
    assert!(ax.at(3, 20).is_finite() && ax.at(35, 20).is_finite());
    let plane = LensPlane::new(Cosmology::default(), 0.3).unwrap();
    let z_source = 2.0;
    let f = plane.distance_ratio(z_source).unwrap();
    let products = Products::from_deflection(ax, ay, plane, reference, z_source).unwrap();
    let (kappa, mu) = (&products.maps.kappa, &products.magnification);
    let blank = |m: &wslap::Map| m.data.iter().filter(|v| v.is_nan()).count();
    assert_eq!(blank(kappa), expected.total());
    assert_eq!(blank(mu), expected.total());
    // Inside, kappa is the SIS's theta_E / (2 r), next to the blank pixel too (one-sided
    // differences; 5% covers the finite differences' truncation at r >= 2 arcsec).
    let g = kappa.geometry;
    for (i, j) in [(10, 20), (29, 25), (31, 25), (30, 24), (20, 8), (33, 33)] {
        let r = g.pixel_center(i, j).length();
        let want = 6.0 / (2.0 * r);
        let got = kappa.at(i, j);
        assert!(
            (got - want).abs() < 0.05 * want,
            "kappa({i}, {j}) = {got}, SIS {want}"
        );
    }
    // The tangential curve is the circle f theta_E, closed inside the data.
    let theta_e = products.curves.einstein_radius_arcsec;
    assert!(
        (theta_e - f * 6.0).abs() < 0.02 * f * 6.0,
        "{theta_e} vs {}",
        f * 6.0
    );
    // The profile stops before the first pixel without data (the one at r = 5.9 arcsec).
    let edges = &products.profile.r_edges_arcsec;
    let last = edges[edges.len() - 1];
    assert!(last > 4.0 && last < 5.93, "{last}");
    assert!(products.profile.kappa.iter().all(|k| k.is_finite()));
    // The written FITS files keep the blank pixels as NaN.
    for (name, bytes) in products.fits_files().unwrap() {
        let back = read_image(&bytes, name).unwrap();
        assert_eq!(back.non_finite_count(), expected.total(), "{name}");
    }
}

/// The real published files (../shared/data, read natively).
#[cfg(not(target_arch = "wasm32"))]
mod galaxies_of_a_par {
    use super::add_galaxies;
    use glam::DVec2;
    use wslap::{parse_par, Dataset, InputText, InputTexts};

    fn read(rel: &str) -> String {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/data")
            .join(rel);
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    const AS1063: &str = "AS1063/lenstool_cats/";

    fn as1063(members: bool) -> Dataset {
        let images = read(&format!("{AS1063}cats_gold_mul_gold.cat"));
        let cat = read(&format!("{AS1063}cats_gold_ref_potential_w_clumpNE.cat"));
        let files = InputTexts {
            images: Some(InputText {
                name: "gold.cat",
                text: &images,
            }),
            members: members.then_some(InputText {
                name: "members.cat",
                text: &cat,
            }),
            ..InputTexts::default()
        };
        Dataset::read(&files, 0.2).unwrap()
    }

    #[test]
    fn the_as1063_bcg_of_the_par_becomes_a_member_once() {
        let par = parse_par(&read(&format!("{AS1063}cats_gold_bestopt.par")), "best.par").unwrap();
        // O1 (core 99 kpc) is the cluster, O4 (49 kpc) a group, O2 a shear: only the BCG, O3.
        let found = par.galaxies().unwrap();
        let rows = found.members;
        assert!(found.without_mag.is_empty());
        assert_eq!(rows.len(), 1);
        let o3 = &rows[0];
        assert_eq!((o3.id.as_str(), o3.mag), ("O3", 17.037));
        assert_eq!(o3.position, DVec2::new(0.006, 0.037));
        // b / a from Lenstool's ellipticity (a^2 - b^2) / (a^2 + b^2) = 0.271.
        let (a, b) = (o3.a_arcsec, o3.b_arcsec);
        assert!(((a * a - b * b) / (a * a + b * b) - 0.271).abs() < 1e-12);

        let mut data = as1063(true);
        let before = data.members.as_ref().unwrap().members.len();
        let notes = add_galaxies(&mut data, &par);
        let members = &data.members.as_ref().unwrap().members;
        assert_eq!(members.len(), before + 1);
        let added = members.last().unwrap();
        // Where the .par puts it on the sky, in the images' frame (lenstool offsets:
        // x = -(RA - RA0) cos Dec0 * 3600, y = (Dec - Dec0) * 3600).
        let frame = data.reference().unwrap();
        let r = par.reference.unwrap();
        let dec = r.dec_deg + 0.037 / 3600.0;
        let ra = r.ra_deg - 0.006 / 3600.0 / r.dec_deg.to_radians().cos();
        let expected = DVec2::new(
            -(ra - frame.ra_deg) * frame.dec_deg.to_radians().cos() * 3600.0,
            (dec - frame.dec_deg) * 3600.0,
        );
        assert!(
            (added.position - expected).length() < 1e-3,
            "{}",
            added.position
        );
        // Then one sentence for the cluster's halo (O1, 99 kpc) and the north-east group's
        // (O4, 49 kpc), which the grid models.
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[1].ends_with(
                "`potentiel O1` (line 27, core 99 kpc) and `potentiel O4` (line 70, core 49 \
                 kpc) have cores wider than a galaxy's (over 5 kpc): not fitted as members; the \
                 grid models their mass"
            ),
            "{notes:?}"
        );
        assert!(
            notes[0].starts_with("best.par: line 55: galaxy O3 at (")
                && notes[0].ends_with(" arcsec, mag 17.04, fitted as a member"),
            "{}",
            notes[0]
        );
        // Given twice, or with a catalogue that has it, it is not added again.
        let notes = add_galaxies(&mut data, &par);
        assert_eq!(data.members.as_ref().unwrap().members.len(), before + 1);
        assert!(
            notes[0].contains("is member O3 of members.cat already: not added twice"),
            "{notes:?}"
        );
        let named = data.members.as_ref().unwrap();
        assert_eq!(named.ids(&named.par_galaxies), ["O3"]);
        // Without a member catalogue it makes one, in the images' frame.
        let mut alone = as1063(false);
        add_galaxies(&mut alone, &par);
        let made = alone.members.unwrap();
        assert_eq!((made.members.len(), made.reference), (1, Some(frame)));
        assert!((made.members[0].position - expected).length() < 1e-3);
    }

    /// Newton's G in kpc (km/s)^2 / Msun (CODATA 2018 G, IAU nominal solar mass), for the
    /// total mass of a circular dPIE, `(3/2) pi sigma^2 r_cut / G` (Eliasdottir et al. 2007:
    /// `sigma_0^2 = (3/2) sigma^2`, and a dPIE's mass is `pi sigma_0^2 r_cut / G`).
    const G_KPC: f64 = 4.300_917e-6;

    /// The halo mass the member law gives `member`, with the default member settings on
    /// the `.par`'s lens plane.
    fn law_mass(member: &wslap::Member, par: &wslap::LenstoolPar) -> f64 {
        let law = wslap::ReconstructConfig::default().members;
        let mag_star = law.mag_star_on(&par.lens_plane().unwrap());
        law.mass_msun(member.mag, mag_star)
    }

    /// A fitted `.par` lists every galaxy it modelled (A1689's of Limousin et al.: 272), each
    /// with a velocity dispersion and radii but no `mag`: each becomes a member whose halo
    /// has its dPIE's mass under the member law, and one note says so for all.
    #[test]
    fn galaxies_without_a_magnitude_are_fitted_by_their_mass() {
        let galaxy = |n: usize, x: f64, sigma: f64, cut: f64| {
            format!(
                "potentiel {n}\n    profil 81\n    x_centre {x}\n    y_centre 0.\n    \
                 v_disp {sigma}\n    core_radius_kpc 0.1\n    cut_radius_kpc {cut}\n    \
                 z_lens 0.35\n    end\n"
            )
        };
        let text = format!(
            "runmode\n    reference 3 292.95682 -26.575718\n    end\ncosmologie\n    H0 70.\n    \
             omega 0.3\n    lambda 0.7\n    end\n{}{}{}{}",
            galaxy(1, 10.0, 150.0, 50.0),
            galaxy(2, 20.0, 250.0, 80.0),
            galaxy(3, 30.0, 120.0, 30.0),
            // A node of a grid model: massless, not a galaxy.
            galaxy(4, 40.0, 0.0, 30.0),
        );
        let par = parse_par(&text, "fitted.par").unwrap();
        assert_eq!(par.galaxies().unwrap().without_mag.len(), 3);
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with(
                "fitted.par: 3 galaxies without a `mag` (lines 9, 18, 27) are fitted as members \
                 of the magnitudes whose halo masses under the member law are their dPIEs' (mag"
            ),
            "{notes:?}"
        );
        let members = data.members.as_ref().unwrap();
        assert_eq!(members.ids(&members.par_galaxies), ["1", "2", "3"]);
        for (m, (sigma, cut)) in
            members
                .members
                .iter()
                .zip([(150.0, 50.0), (250.0, 80.0), (120.0, 30.0)])
        {
            let dpie = 1.5 * std::f64::consts::PI * sigma * sigma * cut / G_KPC;
            let mass = law_mass(m, &par);
            assert!(
                (mass / dpie - 1.0).abs() < 1e-3,
                "{} {mass:e} {dpie:e}",
                m.id
            );
        }
        // A cluster halo with a small core is not made a galaxy of a thousand L*.
        let text = text
            .replace("v_disp 250\n", "v_disp 1200\n")
            .replace("cut_radius_kpc 80\n", "cut_radius_kpc 1500\n");
        let par = parse_par(&text, "fitted.par").unwrap();
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        assert!(
            notes.iter().any(|n| n.starts_with(
                "fitted.par: line 18: `potentiel 2` has no \
                 `mag` and a dPIE mass of"
            ) && n.ends_with(
                "a group's halo, not a galaxy's: not fitted as a member; the grid models its mass"
            )),
            "{notes:?}"
        );
        let named = data.members.as_ref().unwrap();
        assert_eq!(named.ids(&named.par_galaxies), ["1", "3"]);
        // A block written twice is two galaxies to Lenstool, and here, with a note; a
        // neighbour within 1 arcsec is a galaxy of its own.
        let twice = format!(
            "{text}{}{}",
            galaxy(1, 10.0, 150.0, 50.0),
            galaxy(5, 10.5, 140.0, 40.0)
        );
        let par = parse_par(&twice, "fitted.par").unwrap();
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        assert!(
            notes.contains(
                &"fitted.par: 1 galaxy is written twice (line 45 repeats line 9): both are \
                  fitted (as Lenstool reads them), which doubles its mass; delete one if that \
                  is not meant"
                    .to_string()
            ),
            "{notes:?}"
        );
        // (Galaxy 2 is the group's halo above.) Both of galaxy 1's blocks are the `.par`'s.
        let members = data.members.unwrap();
        assert_eq!(members.ids(&members.par_galaxies), ["1", "3", "1", "5"]);
        let ids: Vec<&str> = members.members.iter().map(|m| m.id.as_str()).collect();
        assert_eq!(ids, ["1", "3", "1", "5"]);
        // The same halo centred on a catalogue member (MACS J1149's northern group `O4` on
        // member 1824) is not that member: the member stays as it is, the halo is said.
        let mut data = Dataset::default();
        let (catalog, _) = wslap::parse_member_catalog(
            "#REFERENCE 3 292.95682 -26.575718\n7 0.0 0.0 1 1 0 18.5\n",
            "gal.cat",
            None,
        )
        .unwrap();
        data.members = Some(catalog);
        let centred = text.replace("x_centre 20\n", "x_centre 0\n");
        let par = parse_par(&centred, "fitted.par").unwrap();
        let notes = add_galaxies(&mut data, &par);
        assert!(
            notes.iter().any(|n| n.ends_with(
                "not fitted as a member (centred on member 7, which is fitted as a member); \
                 the grid models its mass"
            )),
            "{notes:?}"
        );
    }

    /// A starting `.par` writes where its fit begins, not a mass: MACS J1149's CATS
    /// `m1149.par` gives the lens of SN Refsdal (O7, no catalogue row) 311 km/s and a 206 kpc
    /// cut, outside its own prior of 30 - 70 kpc (the fit: 162 km/s, 55 kpc), and fitted as a
    /// member of that mass it dragged every member's factor to 0.21. A galaxy whose `limit`
    /// block gives uniform priors on its mass is taken at their low ends, and named for a
    /// layer of its own (`free_mass_galaxies`); the k-th `limit`
    /// block is the k-th potential's whatever its header's number (as Lenstool-HPC reads
    /// them); a prior from 0 gives no least mass, so the written value stays; a posterior
    /// (mode 3) keeps the written values, and the model itself is evaluated as written.
    #[test]
    fn a_galaxy_whose_mass_a_limit_block_frees_is_taken_at_its_least_mass() {
        let galaxy = |name: &str, x: f64| {
            format!(
                "potentiel {name}\n    profil 81\n    x_centre {x}\n    y_centre 0.\n    \
                 v_disp 310.\n    core_radius_kpc 0.15\n    cut_radius_kpc 205.\n    \
                 z_lens 0.35\n    end\n"
            )
        };
        let text = format!(
            "runmode\n    reference 3 292.95682 -26.575718\n    end\ncosmologie\n    H0 70.\n    \
             omega 0.3\n    lambda 0.7\n    end\n\
             potentiel 1\n    profil 81\n    v_disp 1000.\n    core_radius_kpc 50.\n    \
             cut_radius_kpc 1000.\n    z_lens 0.35\n    end\n\
             limit 1\n    v_disp 1 800. 1300. 0.1\n    end\n\
             {}limit 6\n    v_disp 1 150. 450. 0.1\n    cut_radius_kpc 1 30. 70. 0.1\n    \
             core_radius_kpc 1 0.01 0.18 0.1\n    ellipticite 1 0. 0.7 0.1\n    end\n\
             {}limit 2\n    v_disp 1 0. 450. 0.1\n    end\n\
             {}limit O9\n    v_disp 3 162. 7. 0.1\n    end\n",
            galaxy("O7", 10.0),
            galaxy("O8", 20.0),
            galaxy("O9", 30.0),
        );
        let par = parse_par(&text, "start.par").unwrap();
        // The second `limit` block (`limit 6`, line 28) is the second potential's.
        assert_eq!(
            par.potentials[1].free_mass,
            Some(wslap::FreeMass {
                line: 28,
                sigma_v_km_s: Some(150.0),
                r_core: Some(wslap::Radius::Kpc(0.01)),
                r_cut: Some(wslap::Radius::Kpc(30.0)),
            })
        );
        assert_eq!(
            par.potentials[2].free_mass,
            Some(wslap::FreeMass {
                line: 43,
                sigma_v_km_s: None,
                r_core: None,
                r_cut: None,
            })
        );
        assert_eq!(
            par.potentials[3].free_mass, None,
            "a posterior is not a free mass"
        );
        assert!(par.warnings.is_empty(), "{:?}", par.warnings);
        // A uniform prior written upside down is not read, and said: v_disp is as written.
        let upside_down = text.replace("v_disp 1 150. 450. 0.1", "v_disp 1 450. 150. 0.1");
        let par_ud = parse_par(&upside_down, "start.par").unwrap();
        let free = par_ud.potentials[1].free_mass.as_ref().unwrap();
        assert_eq!(free.sigma_v_km_s, None);
        assert_eq!(free.r_cut, Some(wslap::Radius::Kpc(30.0)));
        let said: Vec<String> = par_ud.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            said,
            [
                "start.par:29: `v_disp 1 450. 150. 0.1` in `limit 6` (line 28) is not a uniform \
              prior `1 low high` with 0 <= low <= high: not read, so `v_disp` keeps its \
              written value"
            ]
        );
        // A radius's kpc line wins over its arcsec line whatever it says (as in a `potentiel`
        // block): a malformed kpc line keeps the written cut, said, and the arcsec line's
        // prior is not used instead.
        let both = text.replace(
            "cut_radius_kpc 1 30. 70. 0.1",
            "cut_radius_kpc 1 70. 30. 0.1\n    cut_radius 1 5. 10. 0.1",
        );
        let par_both = parse_par(&both, "start.par").unwrap();
        let free = par_both.potentials[1].free_mass.as_ref().unwrap();
        assert_eq!(free.sigma_v_km_s, Some(150.0));
        assert_eq!(
            free.r_cut, None,
            "the arcsec line is not read beside a kpc line"
        );
        assert_eq!(par_both.warnings.len(), 1, "{:?}", par_both.warnings);
        assert!(
            par_both.warnings[0]
                .to_string()
                .contains("`cut_radius_kpc 1 70. 30. 0.1` in `limit 6`"),
            "{:?}",
            par_both.warnings
        );
        // Without the kpc line the arcsec line's prior is the cut's.
        let arcsec = text.replace("cut_radius_kpc 1 30. 70. 0.1", "cut_radius 1 5. 10. 0.1");
        let par_arcsec = parse_par(&arcsec, "start.par").unwrap();
        let free = par_arcsec.potentials[1].free_mass.as_ref().unwrap();
        assert_eq!(free.r_cut, Some(wslap::Radius::Arcsec(5.0)));
        assert!(par_arcsec.warnings.is_empty(), "{:?}", par_arcsec.warnings);
        // A mode this reader does not know is said too; the value stays as written.
        let mode_2 = text.replace("v_disp 1 150. 450. 0.1", "v_disp 2 150. 450. 0.1");
        let par_2 = parse_par(&mode_2, "start.par").unwrap();
        let free = par_2.potentials[1].free_mass.as_ref().unwrap();
        assert_eq!(free.sigma_v_km_s, None);
        let said: Vec<String> = par_2.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            said,
            [
                "start.par:29: `v_disp 2 150. 450. 0.1` in `limit 6` (line 28) is not a prior \
                 of mode 0 (fixed), 1 (uniform) or 3 (Gaussian): not read, so `v_disp` keeps \
                 its written value"
            ]
        );
        // The model is Lenstool's: O7 as written.
        let wslap::ParComponent::Dpie { sigma_v_km_s, .. } = par.potentials[1].component else {
            panic!("{:?}", par.potentials[1])
        };
        assert_eq!(sigma_v_km_s, 310.0);
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        let said = |n: &str| notes.contains(&n.to_string());
        assert!(
            said(
                "start.par: line 19: `potentiel O7`'s mass is left free by its `limit` block \
                 (line 28), so its written values are where a fit starts, not a mass: it is \
                 taken at the priors' low ends where they are above 0 (v_disp 150 km/s, core \
                 0.01 kpc, cut 30 kpc), in a layer of its own: its factor C is not the members'"
            ),
            "{notes:?}"
        );
        assert!(
            said(
                "start.par: line 34: `potentiel O8`'s mass is left free by its `limit` block \
                 (line 43), so its written values are where a fit starts, not a mass: it is \
                 taken at the priors' low ends where they are above 0 (v_disp 310 km/s, core \
                 0.15 kpc, cut 205 kpc), in a layer of its own: its factor C is not the members'"
            ),
            "{notes:?}"
        );
        let members = data.members.unwrap();
        assert_eq!(members.ids(&members.par_galaxies), ["O7", "O8", "O9"]);
        assert_eq!(members.ids(&members.free_mass_galaxies), ["O7", "O8"]);
        let masses = [(150.0, 30.0), (310.0, 205.0), (310.0, 205.0)];
        for (m, (sigma, cut)) in members.members.iter().zip(masses) {
            let dpie = 1.5 * std::f64::consts::PI * sigma * sigma * cut / G_KPC;
            let mass = law_mass(m, &par);
            assert!(
                (mass / dpie - 1.0).abs() < 1e-3,
                "{} {mass:e} {dpie:e}",
                m.id
            );
        }
    }

    /// Every dPIE of the lens plane with a core too wide for a galaxy is named in a note,
    /// with its line and core: the cluster's halos, a group's with a `mag`, and a galaxy a
    /// set-up fits one by one with a wide core (COOL J1153's three, 7 - 19 kpc, no `mag`;
    /// they were left to the grid without a word). One alone has a sentence of its own.
    #[test]
    fn halos_too_wide_for_a_galaxy_are_said() {
        let block = |name: &str, x: f64, sigma: f64, core: f64, mag: &str| {
            format!(
                "potentiel {name}\n    profil 81\n    x_centre {x}\n    y_centre 0.\n    \
                 v_disp {sigma}\n    core_radius_kpc {core}\n    cut_radius_kpc 100\n{mag}    \
                 z_lens 0.35\n    end\n"
            )
        };
        let head = "runmode\n    reference 3 292.95682 -26.575718\n    end\ncosmologie\n    \
                    H0 70.\n    omega 0.3\n    lambda 0.7\n    end\n";
        let text = format!(
            "{head}{}{}{}{}",
            block("G1", 10.0, 200.0, 12.0, ""),
            block("O1", 0.0, 1000.0, 80.0, ""),
            block("O2", 40.0, 300.0, 30.0, "    mag 19.0\n"),
            // A galaxy with a galaxy's core: fitted, not named here.
            block("G3", 20.0, 150.0, 0.2, "    mag 20.0\n"),
        );
        let par = parse_par(&text, "wide.par").unwrap();
        let found = par.galaxies().unwrap();
        let ids: Vec<&str> = found.members.iter().map(|m| m.id.as_str()).collect();
        assert_eq!(ids, ["G3"]);
        assert!(found.without_mag.is_empty());
        let halos: Vec<(&str, usize)> = found
            .halos
            .iter()
            .map(|h| (h.block.as_str(), h.line))
            .collect();
        assert_eq!(
            halos,
            [
                ("potentiel G1", 9),
                ("potentiel O1", 18),
                ("potentiel O2", 27)
            ]
        );
        assert!((found.halos[0].core_kpc - 12.0).abs() < 1e-9);
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        assert!(
            notes.contains(
                &"wide.par: `potentiel G1` (line 9, core 12 kpc), `potentiel O1` (line 18, core \
                  80 kpc) and `potentiel O2` (line 27, core 30 kpc) have cores wider than a \
                  galaxy's (over 5 kpc): not fitted as members; the grid models their mass"
                    .to_string()
            ),
            "{notes:?}"
        );
        let named = data.members.as_ref().unwrap();
        assert_eq!(named.ids(&named.par_galaxies), ["G3"]);
        let one = format!("{head}{}", block("O1", 0.0, 1000.0, 80.0, ""));
        let par = parse_par(&one, "one.par").unwrap();
        let mut data = Dataset::default();
        assert_eq!(
            add_galaxies(&mut data, &par),
            [
                "one.par: `potentiel O1` (line 9, core 80 kpc) has a core wider than a galaxy's \
              (over 5 kpc): not fitted as a member; the grid models its mass"
            ]
        );
        // A halo of another plane is not the cluster's: not named here.
        let other = format!(
            "{head}{}{}",
            block("G3", 20.0, 150.0, 0.2, "    mag 20.0\n"),
            block("O1", 0.0, 1000.0, 80.0, "").replace("z_lens 0.35\n", "z_lens 1.2\n")
        );
        let options = wslap::ParOptions::default().for_galaxies();
        let par = wslap::parse_par_with(&other, "other.par", &options).unwrap();
        assert_eq!(par.z_lens, 0.35);
        assert!(par.galaxies().unwrap().halos.is_empty());
    }

    #[test]
    fn a_galaxy_without_a_magnitude_takes_its_commented_row_or_its_mass() {
        // MACS1931's .par is a starting model: its BCG (potential 3, core 0.115 kpc, at the
        // reference) has a velocity dispersion to fit and no `mag`; m1931.cat comments its row
        // out (`#1009.0 0.0 0.0 ... 17.325`).
        let par = parse_par(&read("MACS1931/lenstool_cats/m1931.par"), "m1931.par").unwrap();
        let found = par.galaxies().unwrap();
        assert!(found.members.is_empty());
        let [bcg] = &found.without_mag[..] else {
            panic!("{:?}", found.without_mag)
        };
        assert_eq!(
            (bcg.block.as_str(), bcg.line, bcg.centre),
            ("potentiel 3", 66, DVec2::ZERO)
        );
        // Without a member catalogue its magnitude is the one its starting mass implies
        // (v_disp 100 km/s, cut 100 kpc: its `limit` priors start at 0, which gives no least
        // mass), in a layer of its own.
        let mut data = Dataset::default();
        let notes = add_galaxies(&mut data, &par);
        assert_eq!(notes.len(), 3, "{notes:?}");
        assert_eq!(
            notes[0],
            "m1931.par: line 66: `potentiel 3`'s mass is left free by its `limit` block (line \
             77), so its written values are where a fit starts, not a mass: it is taken at the \
             priors' low ends where they are above 0 (v_disp 100 km/s, core 0.12 kpc, cut 100 \
             kpc), in a layer of its own: its factor C is not the members'"
        );
        assert_eq!(
            notes[2],
            "m1931.par: `potentiel 1` (line 28, core 50 kpc) and `potentiel 2` (line 47, core \
             50 kpc) have cores wider than a galaxy's (over 5 kpc): not fitted as members; the \
             grid models their mass"
        );
        assert!(
            notes[1].starts_with(
                "m1931.par: line 66: galaxy 3 has no `mag`: fitted as a member of mag "
            ),
            "{notes:?}"
        );
        let alone = data.members.as_ref().unwrap();
        assert_eq!(alone.ids(&alone.par_galaxies), ["3"]);
        assert_eq!(alone.ids(&alone.free_mass_galaxies), ["3"]);
        // Its magnitude is the member law's for its mass, not one a file wrote.
        assert_eq!(alone.ids(&alone.mass_galaxies), ["3"]);
        let dpie = 1.5 * std::f64::consts::PI * 100.0 * 100.0 * 100.0 / G_KPC;
        let mass = law_mass(&alone.members[0], &par);
        // Its ellipticity (0.273) lowers a dPIE's mass by 1 - eps^2 (eps the Kassiola-Kovner
        // ellipticity, (1 - sqrt(1 - e^2)) / e).
        let e: f64 = 0.273;
        let eps = (1.0 - (1.0 - e * e).sqrt()) / e;
        assert!(
            (mass / (dpie * (1.0 - eps * eps)) - 1.0).abs() < 1e-3,
            "{mass:e} {dpie:e}"
        );
        // A catalogue member named `3` elsewhere is not `potentiel 3`: a `.par` numbers its
        // potentials as catalogues number their rows. Only the `.par`'s galaxy is its own,
        // with its mass free, in a layer of its own.
        let (catalog, _) = wslap::parse_member_catalog(
            "#REFERENCE 3 292.95682 -26.575718\n3 20.0 0.0 1 1 0 18.5\n",
            "gal.cat",
            None,
        )
        .unwrap();
        let mut data = Dataset {
            members: Some(catalog),
            ..Dataset::default()
        };
        add_galaxies(&mut data, &par);
        let both = data.members.as_ref().unwrap();
        assert_eq!(both.ids(&[0, 1]), ["3", "3"]);
        assert_eq!(both.members[0].line, 2);
        assert_eq!(
            (
                both.par_galaxies.as_slice(),
                both.free_mass_galaxies.as_slice()
            ),
            (&[1][..], &[1][..])
        );
        assert_eq!(both.mass_galaxies, [1]);
        let config = wslap::MemberConfig {
            layers: "bcg".parse().unwrap(),
            ..wslap::MemberConfig::default()
        };
        let grid = wslap::CellGrid::regular(DVec2::ZERO, 80.0, 8, 0.75).unwrap();
        let layers = wslap::build_member_layers(both, &config, &par.lens_plane().unwrap(), &grid)
            .unwrap()
            .layers;
        let members: Vec<(&str, &[usize])> = layers
            .iter()
            .map(|l| (l.name.as_str(), l.members.as_slice()))
            .collect();
        assert_eq!(
            members,
            [
                ("galaxy 3 (mass free in the .par)", &[1][..]),
                ("bcg", &[0][..])
            ]
        );
        // With it, the commented row there becomes a member, once; and the set-up's own
        // galaxy is recorded, so no BCG is looked for among the commented rows.
        let cat = read("MACS1931/lenstool_cats/m1931.cat");
        let mut data = Dataset::read(
            &InputTexts {
                members: Some(InputText {
                    name: "m1931.cat",
                    text: &cat,
                }),
                ..InputTexts::default()
            },
            0.2,
        )
        .unwrap();
        let before = data.members.as_ref().unwrap().members.len();
        let notes = add_galaxies(&mut data, &par);
        assert_eq!(
            notes[..1],
            [
                "m1931.par: line 66: `potentiel 3` has no `mag`; the row m1931.cat comments out \
              there (line 10, galaxy 1009.0, mag 17.32) is fitted as a member"
            ]
        );
        assert_eq!(notes.len(), 2, "{notes:?}");
        let members = data.members.as_ref().unwrap();
        assert_eq!(members.members.len(), before + 1);
        let bcg = members.members.last().unwrap();
        assert_eq!((bcg.id.as_str(), bcg.mag, bcg.line), ("1009.0", 17.325, 10));
        assert!(!members.commented.iter().any(|m| m.id == "1009.0"));
        assert_eq!(members.ids(&members.par_galaxies), ["1009.0"]);
        // Its magnitude is the catalogue's.
        assert!(members.mass_galaxies.is_empty());
        let notes = add_galaxies(&mut data, &par);
        assert!(
            notes[0].ends_with("`potentiel 3` (no `mag`) is member 1009.0 of m1931.cat already"),
            "{notes:?}"
        );
        assert_eq!(data.members.as_ref().unwrap().members.len(), before + 1);
    }
}

/// A real set-up from outside this project (tests/data/lenstool/smacs0723, CC0): its
/// `best.par` loads with the images and members, the three priors its optimiser left at
/// z = 0.1 (in front of the lens) are said and not used, every other prior is taken, and
/// its BCG (`potentiel O2`, no `mag`) takes the row `galcat.cat` comments out.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_published_set_up_s_par_gives_its_priors_and_bcg() {
    use wslap::{Dataset, InputText, InputTexts};
    let images = include_str!("../data/lenstool/smacs0723/arcs.dat");
    let members = include_str!("../data/lenstool/smacs0723/galcat.cat");
    let text = include_str!("../data/lenstool/smacs0723/best.par");
    let mut data = Dataset::read(
        &InputTexts {
            images: Some(InputText {
                name: "arcs.dat",
                text: images,
            }),
            members: Some(InputText {
                name: "galcat.cat",
                text: members,
            }),
            ..InputTexts::default()
        },
        0.2,
    )
    .expect("the catalogues load");
    let par = parse_par_with(text, "best.par", &ParOptions::default().for_galaxies())
        .expect("the .par loads");
    let priors = par.redshift_priors.len();
    let notes = data
        .add_par(&par, &par.lens_plane().unwrap(), &Default::default())
        .expect("its galaxies are added");
    let in_front: Vec<&String> = notes
        .iter()
        .filter(|n| n.contains("puts it in front of the lens (z_lens = 0.39): not used"))
        .collect();
    assert_eq!(in_front.len(), 3, "{notes:?}");
    for (note, system) in in_front.iter().zip(["16", "19", "20"]) {
        assert!(
            note.contains(&format!("system {system}'s prior (fixed at 0.1)")),
            "{note}"
        );
    }
    assert_eq!(data.z_priors.len(), priors - 3);
    assert!(
        notes.contains(
            &"best.par: line 69: `potentiel O2` has no `mag`; the row galcat.cat comments out \
              there (line 5, galaxy 4, mag 18.87) is fitted as a member"
                .to_string()
        ),
        "{notes:?}"
    );
    // The 141 potfile members the best.par writes out again are members already, in one note.
    assert!(
        notes.iter().any(
            |n| n.starts_with("best.par: 141 galaxies (lines 108, 122, 136, ")
                && n.ends_with(") are members of galcat.cat already: not added twice")
        ),
        "{notes:?}"
    );
    let m = data.members.as_ref().unwrap();
    assert_eq!(m.ids(&m.par_galaxies), ["4"]);
    assert!(m.members.iter().any(|g| g.id == "4" && g.line == 5));
}

/// Arclets without a redshift (z = 0) take the z_source of the `.par`'s `source` block, as
/// Lenstool gives it to "sources without redshift" (its manual's `source` section: default
/// 0.8); a `.par` that draws the redshifts from a distribution (`dist_z` 1 or 2) is named in
/// the refusal, and so is a z_source that is not a redshift.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arclets_without_a_redshift_take_the_par_s_z_source() {
    let base = "runmode\n\treference 3 342.1832 -44.5309\n\tend\n\
        potentiel O1\n\tprofil 81\n\tx_centre 0.0\n\ty_centre 0.0\n\tellipticite 0.2\n\
        \tangle_pos 10.0\n\tcore_radius_kpc 50.0\n\tcut_radius_kpc 1500.0\n\tv_disp 1100.0\n\
        \tz_lens 0.32\n\tend\n\
        cosmologie\n\tH0 70.0\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\n";
    // The `source` block opens on line 20: its first keyword is on line 21.
    let par = |source: &str| parse_par(&format!("{base}{source}fini\n"), "x.par").unwrap();
    let arclets = "#REFERENCE 3 342.1832 -44.5309\n\
        1 60 10 0.5 0.3 20 1.5\n2 70 -5 0.5 0.3 20 0\n3 -40 25 0.6 0.4 70 0\n";
    let read = |answer: &Result<wslap::UnknownSourceZ, String>| {
        let files = wslap::InputTexts {
            shear: Some(wslap::InputText {
                name: "arclets.cat",
                text: arclets,
            }),
            unknown_source_z: Some(answer),
            ..Default::default()
        };
        wslap::Dataset::read(&files, 0.2)
    };

    let given = par("source\n\tgrid 0\n\tz_source 1.8\n\tdist_z 0\n\tend\n").unknown_source_z();
    let data = read(&given).unwrap();
    let z: Vec<f64> = data.shear.unwrap().arclets.iter().map(|a| a.z).collect();
    assert_eq!(z, [1.5, 1.8, 1.8]);
    let said = "arclets.cat: line 3: 2 arclets without a redshift (z = 0) put at z = 1.8, as \
                Lenstool does: z_source 1.8 of x.par's `source` block (line 22)";
    assert!(
        data.warnings.iter().any(|w| w == said),
        "{:?}",
        data.warnings
    );

    // No z_source (or no `source` block): Lenstool's default.
    for source in ["", "source\n\tgrid 0\n\tend\n"] {
        let default = par(source).unknown_source_z();
        let data = read(&default).unwrap();
        assert_eq!(data.shear.unwrap().arclets[2].z, 0.8);
        let said = "put at z = 0.8, as Lenstool does: Lenstool's default 0.8: x.par gives no \
                    z_source";
        assert!(
            data.warnings.iter().any(|w| w.ends_with(said)),
            "{:?}",
            data.warnings
        );
    }

    // A distribution: the first row without a redshift is refused, naming the .par's line.
    let smail = par("source\n\tdist_z 2 0.44 2.94\n\tsmail 2. 1.3 1.8\n\tend\n").unknown_source_z();
    let err = read(&smail).unwrap_err().to_string();
    assert!(
        err.starts_with(
            "arclets.cat: line 3, column 7 (z): '0' is 0 (unknown): x.par (line 21: dist_z 2 \
             0.44 2.94) draws the redshifts of sources without one from a distribution (the \
             Smail et al. law of its `smail` line), which this tool does not model; write each \
             arclet's redshift"
        ),
        "{err}"
    );
    let uniform = par("source\n\tdist_z 1 1.0 3.0\n\tend\n").unknown_source_z();
    assert!(uniform
        .unwrap_err()
        .contains("uniform between two redshifts"));
    let bad = par("source\n\tz_source -1\n\tend\n").unknown_source_z();
    assert_eq!(
        bad.unwrap_err(),
        "x.par (line 21): z_source '-1' is not a redshift (a number above 0)"
    );
    // Without a .par the row is refused with what to do.
    let files = wslap::InputTexts {
        shear: Some(wslap::InputText {
            name: "arclets.cat",
            text: arclets,
        }),
        ..Default::default()
    };
    let err = wslap::Dataset::read(&files, 0.2).unwrap_err().to_string();
    assert!(err.contains("give that .par with the catalogue"), "{err}");
}

/// A galaxy a `.par` writes twice (with its `mag`) is fitted twice, as Lenstool sums every
/// potential, and said; when the member catalogue lists it, neither copy is added and no
/// repeat is said.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_galaxy_written_twice_is_fitted_twice_unless_catalogued() {
    let galaxy = "potentiel 569\n\tprofil 81\n\tx_centre -73.383\n\ty_centre -30.375\n\t\
                  ellipticite 0.237\n\tangle_pos -47.2\n\tcore_radius_kpc 0.169\n\t\
                  cut_radius_kpc 64.372\n\tv_disp 152.621\n\tmag 20.38\n\tz_lens 0.544\n\tend\n";
    let text = format!(
        "runmode\n\treference 3 177.398750 22.398530\n\tend\n\
         cosmologie\n\tH0 70.0\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\n{galaxy}{galaxy}fini\n"
    );
    let par = parse_par(&text, "best.par").unwrap();
    let mut data = wslap::Dataset::default();
    let notes = add_galaxies(&mut data, &par);
    assert!(
        notes.iter().any(|n| n.starts_with(
            "best.par: 1 galaxy is written twice (line 21 repeats line 9): both are fitted"
        )),
        "{notes:?}"
    );
    assert_eq!(data.members.unwrap().members.len(), 2);
    let (catalog, _) = wslap::parse_member_catalog(
        "#REFERENCE 3 177.398750 22.398530\n569 -73.383 -30.375 1 0.8 -47.2 20.38\n",
        "gal.cat",
        None,
    )
    .unwrap();
    let mut data = wslap::Dataset {
        members: Some(catalog),
        ..Default::default()
    };
    let notes = add_galaxies(&mut data, &par);
    assert!(
        !notes.iter().any(|n| n.contains("written twice")),
        "{notes:?}"
    );
    assert!(
        notes
            .iter()
            .any(|n| n.ends_with(") are members of gal.cat already: not added twice")),
        "{notes:?}"
    );
    assert_eq!(data.members.unwrap().members.len(), 1);
}

/// A file given as another kind is named as what it is: a catalogue or a JSON model given as
/// a `.par`, a `.par` given as a JSON model, a catalogue given as DS9 arcs (a newcomer's
/// mistakes, each once answered with a parser's words: "no `cosmologie` block", "expected
/// value", "region shape `1`").
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_file_of_another_kind_is_named_as_what_it_is() {
    let catalogue = "#REFERENCE 0\n1.1 10.2 -3.1 0.1 0.1 0 2.0 25\n1.2 -8.0 4.0 0.1 0.1 0 2.0 25\n";
    let err = refused(catalogue, "images.cat");
    assert!(
        err.starts_with("images.cat: no `cosmologie` block: this looks like a Lenstool catalogue")
            && err.contains("give it with --images or --members"),
        "{err}"
    );
    let json = "{\"z_lens\": 0.3, \"components\": []}";
    let err = refused(json, "model.json");
    assert!(
        err.contains(
            "this looks like a JSON model file, not a Lenstool .par (give it with --model)"
        ),
        "{err}"
    );
    // A .par without a cosmology block that is neither keeps the plain reason.
    let err = refused("runmode\n  reference 3 10 20\n  end\n", "bare.par");
    assert!(err.ends_with("no `cosmologie` block"), "{err}");

    let err = wslap::ModelFile::from_json_str(IDENTITY, "identity.par")
        .expect_err("a .par is no JSON model")
        .to_string();
    assert!(
        err.contains(
            "this is a Lenstool parameter file (.par), not a JSON model: give it with --lenstool"
        ),
        "{err}"
    );
    let first = IDENTITY
        .lines()
        .position(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .unwrap();
    assert!(
        err.contains(&format!("line {}, column 1", first + 1)),
        "{err}"
    );

    let err = wslap::read_regions(catalogue, "arcs.reg").expect_err("a catalogue is no DS9 file");
    let err = err.to_string();
    assert!(
        err.starts_with("arcs.reg line 2: region shape `1` is not supported")
            && err.contains("reads as a Lenstool catalogue row")
            && err.contains("give the catalogue with --images"),
        "{err}"
    );
}
