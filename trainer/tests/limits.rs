//! The trainer's size limits are the core's: a model at each limit is written (and loads in the
//! core in f32 and Q16.16), one past it is refused before anything is written, naming the
//! limit and the option that fits.

use neurosurf_core::implicit::{DEFAULT_MODULES, MAX_GUARDS, MODULE_PARAMETERS};
use neurosurf_core::parametric::{
    DEFAULT_PARAMETERS as DEFAULT_NETWORK_PARAMETERS, MAX_HIDDEN_LAYERS, MAX_NEURONS,
};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::blob::write_checked;
use neurosurf_trainer::implicit::{self, Guard, ImplicitNetwork, TreeSpec};
use neurosurf_trainer::parametric::{
    Activation, SurfaceNetwork, check_capacity, largest_parameter_count, network_to_blob,
};

const SCALARS: [ScalarKind; 2] = [ScalarKind::F32, ScalarKind::Q16_16];

/// A balanced tree over the features `first..first + count`.
fn balanced(first: u32, count: u32) -> TreeSpec {
    if count == 1 {
        return TreeSpec::Leaf(first);
    }
    let left = count / 2;
    TreeSpec::node(balanced(first, left), balanced(first + left, count - left))
}

/// The blob of an (untrained) implicit model of `leaves` leaves at `width` with as many sign
/// guards as a model may hold (what training may add), as `scalar`.
fn implicit_blob(leaves: usize, width: usize, scalar: ScalarKind) -> Vec<u8> {
    let guard = Guard {
        center: [0.0; 3],
        inverse_radius: 1.0,
        amplitude: -0.5,
    };
    let network = ImplicitNetwork::new(width, &balanced(0, leaves as u32))
        .unwrap()
        .with_guards(vec![guard; MAX_GUARDS]);
    implicit::to_blob(&network, None, scalar).unwrap()
}

/// Writes `bytes` over a file holding "kept"; returns the error, and checks that the old
/// content survived a refusal.
fn write_over_existing(bytes: &[u8]) -> Option<String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.nsb");
    std::fs::write(&path, b"kept").unwrap();
    match write_checked(&path, bytes) {
        Ok(()) => {
            assert_eq!(std::fs::read(&path).unwrap(), bytes);
            None
        }
        Err(error) => {
            assert_eq!(std::fs::read(&path).unwrap(), b"kept", "{error}");
            Some(error.to_string())
        }
    }
}

#[test]
fn implicit_models_at_the_parameter_limit_are_written_and_one_feature_more_is_refused() {
    for width in [6, 9, 12] {
        let most = (1..=DEFAULT_MODULES)
            .rev()
            .find(|&k| implicit::fits(k, width))
            .unwrap();
        let (_, parameters) = implicit::model_size(most + 1, width);
        assert!(parameters > MODULE_PARAMETERS || 2 * most + 1 > DEFAULT_MODULES);
        implicit::check_capacity(most, width).unwrap();
        let error = implicit::check_capacity(most + 1, width)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(&format!("--features {most} or fewer")),
            "{error}"
        );
        for scalar in SCALARS {
            assert_eq!(
                write_over_existing(&implicit_blob(most, width, scalar)),
                None,
                "{most} leaves at width {width} in {scalar:?}"
            );
            // The core agrees: one more leaf does not load.
            let error = write_over_existing(&implicit_blob(most + 1, width, scalar))
                .expect("one leaf past the limit is refused");
            assert!(error.contains("model.nsb"), "{error}");
        }
    }
}

#[test]
fn implicit_models_at_the_module_limit_are_written_and_one_feature_more_is_refused() {
    // Width 1 keeps the parameters far below their limit: the modules bind.
    let most = DEFAULT_MODULES.div_ceil(2);
    assert!(implicit::fits(most, 1));
    assert!(!implicit::fits(most + 1, 1));
    let error = implicit::check_capacity(most + 1, 1)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!("{DEFAULT_MODULES} modules")),
        "{error}"
    );
    for scalar in SCALARS {
        assert_eq!(write_over_existing(&implicit_blob(most, 1, scalar)), None);
        assert!(write_over_existing(&implicit_blob(most + 1, 1, scalar)).is_some());
    }
}

/// A surface network with `hidden` layer sizes, every parameter a small distinct value.
fn surface_network(hidden: &[usize]) -> SurfaceNetwork {
    let mut network = SurfaceNetwork::zeros(
        hidden,
        Activation::default(),
        [0.5, 0.5],
        [0.5, 0.5],
        [0.0; 3],
        1.0,
    )
    .unwrap();
    let values: Vec<f64> = (0..network.parameter_count())
        .map(|i| ((i * 37 % 101) as f64 - 50.0) / 100.0)
        .collect();
    network.set_parameters(&values).unwrap();
    network
}

#[test]
fn surface_networks_at_the_size_limits_are_written_and_one_past_is_refused() {
    // The widest network of MAX_HIDDEN_LAYERS layers the core's parameter capacity holds.
    let widest = (1..=MAX_NEURONS)
        .rev()
        .find(|&n| largest_parameter_count(MAX_HIDDEN_LAYERS, n) <= DEFAULT_NETWORK_PARAMETERS)
        .unwrap();
    check_capacity(MAX_HIDDEN_LAYERS, widest).unwrap();
    let error = check_capacity(MAX_HIDDEN_LAYERS, widest + 1)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!("--max-neurons {widest} or fewer"))
            && error.contains(&DEFAULT_NETWORK_PARAMETERS.to_string()),
        "{error}"
    );
    // One layer of the most neurons fits too.
    check_capacity(1, MAX_NEURONS).unwrap();
    for scalar in SCALARS {
        for at_limit in [vec![widest; MAX_HIDDEN_LAYERS], vec![MAX_NEURONS]] {
            let bytes = network_to_blob(&surface_network(&at_limit), None, scalar).unwrap();
            assert_eq!(write_over_existing(&bytes), None, "{at_limit:?} {scalar:?}");
        }

        let error = network_to_blob(
            &surface_network(&[widest + 1; MAX_HIDDEN_LAYERS]),
            None,
            scalar,
        )
        .unwrap_err()
        .to_string();
        assert!(
            error.contains(&DEFAULT_NETWORK_PARAMETERS.to_string()),
            "{error}"
        );

        let deeper = vec![1; MAX_HIDDEN_LAYERS + 1];
        let error = network_to_blob(&surface_network(&deeper), None, scalar)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(&format!("{} hidden layers", MAX_HIDDEN_LAYERS + 1))
                && error.contains(&format!("at most {MAX_HIDDEN_LAYERS}")),
            "{error}"
        );

        let wider = [MAX_NEURONS + 1];
        let error = network_to_blob(&surface_network(&wider), None, scalar)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(&format!("{} neurons", MAX_NEURONS + 1))
                && error.contains(&format!("at most {MAX_NEURONS}")),
            "{error}"
        );
    }
}
