//! `quadwalk results`: a tiny plan gives every page, the cache is reused
//! and refreshed, and a bad plan is refused with its name.

use std::path::Path;

use super::train::{s, scratch_dir};
use super::{failure, quadwalk};

/// The size of a PNG file, read from its IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG", "{} is a PNG", path.display());
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_tiny_plan_writes_table_one_fig_four_the_matrix_and_the_ablations() {
    let dir = scratch_dir("results-tiny");
    let rigid_policy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/rigid");
    let rigid_policy = s(&rigid_policy);
    let plan = dir.join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "[evaluation]\nepisodes = 1\nphases = 4\nseed_sets = [7, 9]\n\n[scenarios]\ntv2 = \"scripted\"\ntv8 = \"scripted\"\ntc2 = \"scripted\"\ntc5 = \"scripted\"\n\n[matrix]\npolicies = [\"scripted\", \"{rigid_policy}\"]\nterrains = [\"rigid\", \"rigid:friction=0.4\"]\n\n[[ablation]]\nvariant = \"full observation\"\nseed = 0\npolicy = \"{rigid_policy}\"\nterrain = \"rigid\"\n\n[[ablation]]\nvariant = \"full observation\"\nseed = 1\npolicy = \"{rigid_policy}\"\nterrain = \"rigid\"\n"
        ),
    )
    .unwrap();
    let out = dir.join("pages");
    let cache = dir.join("cache");
    let args = [
        "results",
        "--plan",
        s(&plan),
        "--out",
        s(&out),
        "--cache",
        s(&cache),
        "--threads",
        "2",
    ];
    let run = quadwalk(&args);
    let stderr = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(run.status.success(), "{stderr}");
    // the crawl on the scenarios' four terrains and on the matrix's two,
    // the policy on the two; the ablation's cell is the policy's on rigid
    let evaluated = stderr.matches(" episodes x 4 phases").count();
    assert_eq!(evaluated, 4 + 2 + 2, "{stderr}");

    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    assert!(
        table.contains(
            "| cm, ours / paper | T_v2^ave | T_v2^2 | T_v2^5 | T_v8^2 | T_v8^5 | T_c^2 | T_c^5 |"
        ),
        "{table}"
    );
    for row in [
        "sigma(h_b)",
        "mu(h_b)",
        "mu(fr)",
        "mu(fl)",
        "mu(rr)",
        "mu(rl)",
    ] {
        assert!(table.contains(&format!("| {row} |")), "{row}: {table}");
    }
    assert!(table.contains(" / 33.1 |"), "the paper's T_v2^ave mu(h_b)");
    assert!(table.contains("(a) The paper: T_c^2 and T_c^5"), "{table}");
    assert!(
        table.contains(
            "quadwalk eval --policy scripted --terrain elastic:5cm --episodes 1 --phases 4 --seed 9"
        ),
        "each evaluation's command: {table}"
    );
    assert_eq!(png_size(&out.join("fig4.png")), (1024, 640));

    let matrix = std::fs::read_to_string(out.join("matrix.md")).unwrap();
    assert!(
        matrix.contains("| scripted | `rigid:friction=0.4` | "),
        "{matrix}"
    );
    assert!(matrix.contains(&format!("| {rigid_policy} |")), "{matrix}");
    let ablations = std::fs::read_to_string(out.join("ablations.md")).unwrap();
    assert!(
        ablations.contains("| full observation | 0 |")
            && ablations.contains("| full observation | 1 |"),
        "a row per training seed: {ablations}"
    );
    // the two seeds (here the same policy) pooled: each run's two
    // episodes, then all four
    let pooled = ablations
        .lines()
        .find(|l| l.starts_with("| full observation | 0, 1 | "))
        .unwrap_or_else(|| panic!("a row per variant: {ablations}"));
    let cells: Vec<&str> = pooled.split('|').map(str::trim).collect();
    let per_seed: Vec<&str> = cells[3].split(", ").collect();
    assert_eq!(per_seed.len(), 2, "{pooled}");
    assert_eq!(per_seed[0], per_seed[1], "{pooled}");
    let (one, two) = per_seed[0].split_once('/').unwrap();
    let (all, four) = cells[4].split_once('/').unwrap();
    assert_eq!((two, four), ("2", "4"), "{pooled}");
    assert_eq!(
        all.parse::<usize>().unwrap(),
        2 * one.parse::<usize>().unwrap(),
        "{pooled}"
    );
    assert_eq!(png_size(&out.join("ablation-curves.png")), (1024, 640));

    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let cells = results.as_array().unwrap();
    assert_eq!(cells.len(), 8);
    for cell in cells {
        assert_eq!(cell["summary"]["episodes"], 2, "two seed sets of one");
        assert_eq!(cell["seeds"].as_array().unwrap().len(), 2);
    }

    // again: every evaluation comes from the cache, the pages are the same
    let again = quadwalk(&args);
    let stderr = String::from_utf8_lossy(&again.stderr).to_string();
    assert!(again.status.success(), "{stderr}");
    assert_eq!(stderr.matches(": from ").count(), 8, "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("table1.md")).unwrap(),
        table
    );
    // --fresh runs them again, to the same figures
    let mut fresh = args.to_vec();
    fresh.push("--fresh");
    let third = quadwalk(&fresh);
    let stderr = String::from_utf8_lossy(&third.stderr).to_string();
    assert!(third.status.success(), "{stderr}");
    assert_eq!(stderr.matches(": from ").count(), 0, "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("matrix.md")).unwrap(),
        matrix
    );

    // --only matrix: the matrix's page from the cache, the other pages and
    // the other sections' entries in results.json as they were
    let whole = std::fs::read_to_string(out.join("results.json")).unwrap();
    std::fs::remove_file(out.join("table1.md")).unwrap();
    std::fs::remove_file(out.join("matrix.md")).unwrap();
    let mut only = args.to_vec();
    only.extend(["--only", "matrix"]);
    let fourth = quadwalk(&only);
    let stderr = String::from_utf8_lossy(&fourth.stderr).to_string();
    assert!(fourth.status.success(), "{stderr}");
    assert_eq!(stderr.matches(": from ").count(), 4, "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("matrix.md")).unwrap(),
        matrix
    );
    assert!(!out.join("table1.md").exists(), "table1.md is not --only's");
    assert_eq!(
        std::fs::read_to_string(out.join("results.json")).unwrap(),
        whole
    );
    // the matrix's entries alone, then put back among the others: each
    // where the whole run wrote it, results.json to the byte
    std::fs::remove_file(out.join("results.json")).unwrap();
    assert!(quadwalk(&only).status.success());
    let alone: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let alone = alone.as_array().unwrap();
    assert_eq!(alone.len(), 4, "{alone:?}");
    let all: serde_json::Value = serde_json::from_str(&whole).unwrap();
    let others: Vec<&serde_json::Value> = all
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| !alone.contains(e))
        .collect();
    assert_eq!(others.len(), 4);
    std::fs::write(
        out.join("results.json"),
        serde_json::to_string_pretty(&others).unwrap(),
    )
    .unwrap();
    assert!(quadwalk(&only).status.success());
    let written = std::fs::read_to_string(out.join("results.json")).unwrap();
    let order = |text: &str| -> Vec<(String, String)> {
        let entries: serde_json::Value = serde_json::from_str(text).unwrap();
        entries
            .as_array()
            .unwrap()
            .iter()
            .map(|e| (e["policy"].to_string(), e["terrain"].to_string()))
            .collect()
    };
    assert_eq!(order(&written), order(&whole));
    assert!(
        written == whole,
        "results.json differs from the whole run's"
    );

    // a section the plan does not have is named
    let mut absent = args.to_vec();
    absent.extend(["--only", "controllers"]);
    let err = failure(&absent, 1);
    assert!(
        err.contains("--only controllers") && err.contains("has no [controllers]"),
        "{err}"
    );
}

#[test]
fn a_tiny_plan_puts_controllers_side_by_side_on_terrains_and_through_a_change() {
    let dir = scratch_dir("results-controllers");
    let rigid_policy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/rigid");
    let rigid_policy = s(&rigid_policy);
    let plan = dir.join("plan.toml");
    // the springs go from 2 cm to 5 cm 4 s after each reset; 14 phases
    // (10.5 s after the 0.5 s settle) cover the response's window
    std::fs::write(
        &plan,
        format!(
            "[evaluation]\nepisodes = 1\nphases = 4\nseed_sets = [7, 9]\n\n[controllers]\nterrains = [\"rigid\"]\nchanges = [\"switch:2cm:5cm:4\"]\nchange_phases = 14\ntask = [\"base_height_reference=feet\"]\n\n[[controllers.row]]\nname = \"crawl\"\npolicy = \"scripted\"\n\n[[controllers.row]]\nname = \"phase level\"\npolicy = \"{rigid_policy}\"\n"
        ),
    )
    .unwrap();
    let out = dir.join("pages");
    let run = quadwalk(&[
        "results",
        "--plan",
        s(&plan),
        "--out",
        s(&out),
        "--cache",
        s(&dir.join("cache")),
        "--threads",
        "2",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(run.status.success(), "{stderr}");
    assert_eq!(
        stderr.matches(" episodes x 4 phases").count(),
        2,
        "{stderr}"
    );
    assert_eq!(
        stderr.matches(" episodes x 14 phases").count(),
        2,
        "{stderr}"
    );
    let page = std::fs::read_to_string(out.join("controllers.md")).unwrap();
    assert!(page.contains("| controller | policy | `rigid` |"), "{page}");
    // both seed sets, then each set's share
    assert!(page.contains("| crawl | scripted | 2/2 (1, 1), "), "{page}");
    assert!(
        page.contains(&format!("| phase level | {rigid_policy} |")),
        "{page}"
    );
    assert!(page.contains("Episodes of 14 phases."), "{page}");
    // the crawl walks through the change on both seeds: a response each
    assert!(
        page.contains("| crawl | `switch:2cm:5cm:4` | 2/2 | -"),
        "a softening lowers the base: {page}"
    );
    assert!(
        page.contains(
            "quadwalk eval --policy scripted --terrain switch:2cm:5cm:4 --task base_height_reference=feet --episodes 1 --phases 14 --seed 9"
        ),
        "{page}"
    );
    assert_eq!(png_size(&out.join("controllers-response.png")), (1024, 640));
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let crawl_change = results
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["policy"] == "scripted" && c["terrain"] == "switch:2cm:5cm:4")
        .unwrap();
    assert_eq!(crawl_change["phases"], 14);
    assert_eq!(
        crawl_change["task_overrides"],
        serde_json::json!(["base_height_reference=feet"])
    );
    assert!(
        page.contains("judged with the task settings `base_height_reference=feet`"),
        "{page}"
    );
    let profile = crawl_change["summary"]["change_response"]["mean_profile_m"]
        .as_array()
        .unwrap();
    assert_eq!(profile.len(), 180, "9 s in bins of 0.05 s");
}

#[test]
fn a_bad_plan_is_refused_with_its_name_and_what_is_wrong() {
    let dir = scratch_dir("results-bad");
    let plan = dir.join("plan.toml");
    std::fs::write(
        &plan,
        "[evaluation]\nepisodes = 1\nphases = 4\nseed_sets = [7]\n[matrix]\npolicies = [\"scripted\"]\nterrains = [\"marsh:5cm\"]\n",
    )
    .unwrap();
    let err = failure(&["results", "--plan", s(&plan)], 1);
    assert!(
        err.contains("plan.toml") && err.contains("marsh:5cm"),
        "{err}"
    );
    let missing = dir.join("no-such-plan.toml");
    let err = failure(&["results", "--plan", s(&missing)], 1);
    assert!(err.contains("no-such-plan.toml"), "{err}");
    assert!(!dir.join("table1.md").exists(), "nothing written");
}
