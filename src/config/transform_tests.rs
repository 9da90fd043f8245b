//! The `formations` transform settings as a config file writes them: defaults,
//! range errors and the gesture map, each error at its line and column.

use crate::config::{Config, DEFAULT_CONFIG_RON};
use crate::vocab::FormationMethod;
use std::path::Path;

fn err(text: &str) -> String {
    Config::from_str(text, Path::new("t.ron"))
        .unwrap_err()
        .to_string()
}

/// `file:line:col` of the first line of `text` containing `needle`.
fn at(text: &str, needle: &str) -> String {
    let (i, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.contains(needle))
        .unwrap();
    let col = line.find(needle).unwrap() + 1;
    format!("t.ron:{}:{col}", i + 1)
}

#[test]
fn the_shipped_config_documents_the_defaults() {
    let c = Config::embedded_default();
    let f = &c.formations;
    assert_eq!(f.method, FormationMethod::Transform);
    assert_eq!(f.cost, crate::config::TransformCost::LeastEffort);
    assert_eq!(f.transform, crate::config::TransformMoveConfig::default());
    assert_eq!(f.subgroups, crate::config::SubgroupsConfig::default());
    assert_eq!(
        f.subgroups.similarity,
        crate::config::SubgroupSimilarity::Local
    );
    let paper = DEFAULT_CONFIG_RON.replace("similarity: local", "similarity: paper");
    let c = Config::from_str(&paper, Path::new("p.ron")).unwrap();
    assert_eq!(
        c.formations.subgroups.similarity,
        crate::config::SubgroupSimilarity::Paper
    );
    let normalised =
        DEFAULT_CONFIG_RON.replace("cost: least_effort", "cost: least_effort_normalised");
    let c = Config::from_str(&normalised, Path::new("n.ron")).unwrap();
    assert_eq!(
        c.formations.cost,
        crate::config::TransformCost::LeastEffortNormalised
    );
    assert!(f.gestures.is_empty());
    // A config without the new fields gets the same.
    let old = DEFAULT_CONFIG_RON
        .replace("        method: transform,\n", "")
        .replace("        cost: least_effort,\n", "");
    let c = Config::from_str(&old, Path::new("o.ron")).unwrap();
    assert_eq!(c.formations.method, FormationMethod::Transform);
}

#[test]
fn bad_transform_values_are_errors_at_their_place() {
    let t = DEFAULT_CONFIG_RON.replace("desired_speed_m_s: 1.3", "desired_speed_m_s: -2.0");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "desired_speed_m_s: -2.0"))
            && e.contains("field `formations.transform.desired_speed_m_s`")
            && e.contains("got -2"),
        "{e}"
    );
    let t = DEFAULT_CONFIG_RON.replace("timeout_s: 120.0", "timeout_s: 0.0");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "timeout_s: 0.0"))
            && e.contains("field `formations.transform.timeout_s`"),
        "{e}"
    );
    let t = DEFAULT_CONFIG_RON.replace("tau_s: 0.4", "tau_s: 0.0");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "tau_s: 0.0")) && e.contains("field `formations.transform.tau_s`"),
        "{e}"
    );
    let t = DEFAULT_CONFIG_RON.replace("damping: 0.7", "damping: 1.0");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "damping: 1.0"))
            && e.contains("field `formations.subgroups.damping`: damping must be in [0.5, 1)"),
        "{e}"
    );
    let t = DEFAULT_CONFIG_RON.replace("similarity: local", "similarity: nearest");
    let e = err(&t);
    assert!(
        e.contains("nearest") && e.contains("paper") && e.contains("t.ron:"),
        "{e}"
    );
    let t = DEFAULT_CONFIG_RON.replace("method: transform", "method: teleport");
    let e = err(&t);
    assert!(e.contains("teleport") && e.contains("mesh"), "{e}");
    let t = DEFAULT_CONFIG_RON.replace("cost: least_effort", "cost: cheapest");
    let e = err(&t);
    assert!(e.contains("cheapest") && e.contains("manhattan"), "{e}");
}

#[test]
fn the_gesture_map_names_known_classes_and_formations() {
    let map = |entries: &str| {
        DEFAULT_CONFIG_RON.replace(
            "        gestures: [],\n",
            &format!("        gestures: [{entries}],\n"),
        )
    };
    let ok =
        map("(class: \"twist\", formation: \"arrow\"), (class: \"expand\", formation: \"start\")");
    let c = Config::from_str(&ok, Path::new("t.ron")).unwrap();
    assert_eq!(c.formations.gestures.len(), 2);
    let t = map("(class: \"twirl\", formation: \"arrow\")");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "class: \"twirl\""))
            && e.contains(
                "field `formations.gestures[0].class`: the gesture library library.ctgl (shipped) has no class `twirl`; its classes are translate"
            )
            && e.contains("twist_while_contracting"),
        "{e}"
    );
    let t =
        map("(class: \"twist\", formation: \"arrow\"), (class: \"split\", formation: \"blob\")");
    let e = err(&t);
    assert!(
        e.contains(&at(&t, "formation: \"blob\""))
            && e.contains(
                "field `formations.gestures[1].formation`: no formation is called `blob`"
            )
            && e.contains("start, square, arrow"),
        "{e}"
    );
    let t =
        map("(class: \"twist\", formation: \"arrow\"), (class: \"twist\", formation: \"line\")");
    let e = err(&t);
    assert!(
        e.contains("`formations.gestures[1].class`: gesture class `twist` is mapped twice"),
        "{e}"
    );
}

#[test]
fn the_subgroup_attraction_is_read_and_a_bad_one_is_located() {
    use crate::config::TransformAttraction;
    let cfg = |text: &str| Config::from_str(text, Path::new("t.ron")).unwrap();
    let shipped = cfg(DEFAULT_CONFIG_RON);
    assert_eq!(
        shipped.formations.transform.subgroup_attraction,
        TransformAttraction::Place
    );
    for (name, want) in [
        ("as_printed", TransformAttraction::AsPrinted),
        ("decaying", TransformAttraction::Decaying),
        ("dt", TransformAttraction::Dt),
    ] {
        let t = DEFAULT_CONFIG_RON.replace(
            "subgroup_attraction: place",
            &format!("subgroup_attraction: {name}"),
        );
        assert_eq!(cfg(&t).formations.transform.subgroup_attraction, want);
    }
    let t = DEFAULT_CONFIG_RON.replace("subgroup_attraction: place", "subgroup_attraction: glue");
    let e = err(&t);
    assert!(
        e.contains("t.ron:") && e.contains("glue") && e.contains("as_printed"),
        "{e}"
    );
}
