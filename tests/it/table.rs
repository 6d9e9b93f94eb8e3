//! `run --table FILE`: every tick a CSV row at full f64 precision, readable without the rerun
//! SDK; the settled values read back from it equal the JSON report's bit for bit.

use crate::common;
use common::tensegrity;
use std::path::Path;
use std::process::Command;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

/// The table's header and rows as text fields.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(str::to_string).collect();
    (header, lines.map(|l| l.split(',').map(str::to_string).collect()).collect())
}

/// mohr2011's trajectory: one row per step of the run (1239), a column per node coordinate,
/// cable tension, actuator force, input and model quantity; the row of the settled tick holds
/// the report's settled simulated values exactly (same f64 bits).
/// What the peer Python `py` prints running `script` (trimmed); its failure fails the test.
fn peer_prints(py: &str, script: &str) -> String {
    let o = Command::new(py).args(["-c", script]).output().expect("the peer Python runs");
    assert!(o.status.success(), "the pandas read failed: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

#[test]
fn the_trajectory_table_holds_the_settled_values_bit_for_bit() {
    let dir = std::env::temp_dir().join(format!("table-{}", std::process::id()));
    let path = dir.join("trajectory.csv");
    let sc = scenario::load(Path::new("scenarios/mohr2011/trajectory.toml")).unwrap();
    let r = run(&sc, &RunOptions { table: Some(path.clone().into()), ..RunOptions::default() });
    assert!(r.passed, "{:?}", r.error);
    assert!(std::fs::read_dir(&dir).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().contains(".partial")));
    let (header, rows) = read_csv(&path);
    assert_eq!(rows.len() as u64, r.settle.steps);
    assert!(rows.iter().all(|row| row.len() == header.len()));
    for c in [
        "tick",
        "time_s",
        "input:rho1",
        "node:B1.z",
        "cable:A2B3.tension_n",
        "actuator:rho1@A3B2.force",
        "sim:z",
        "analytic:z",
    ] {
        assert!(header.iter().any(|h| h == c), "no column {c}: {header:?}");
    }
    let settled = &r.points[0].simulated;
    // A simulated value's column: its own `sim:` one, or the node or member column that holds
    // it (a node coordinate or a member force is not written twice).
    let column_of = |q: &str| {
        let (name, _) = q.rsplit_once('.').unwrap_or((q, ""));
        [format!("sim:{q}"), format!("node:{q}"), format!("spring:{name}.force_n"), format!("cable:{name}.tension_n")]
            .into_iter()
            .find_map(|c| header.iter().position(|h| *h == c))
            .unwrap_or_else(|| panic!("no column holds {q}"))
    };
    let matching: Vec<&Vec<String>> = rows
        .iter()
        .filter(|row| settled.iter().all(|(q, v)| row[column_of(q)].parse::<f64>().unwrap().to_bits() == v.to_bits()))
        .collect();
    assert!(!matching.is_empty(), "no row holds the settled values {settled:?}");
    let tick: u64 = matching[0][0].parse().unwrap();

    // pandas, where a Python with it is at hand (TENSEGRITY_PYTHON or python3): the JSON
    // report and the table read in Python (both parsers exact), the settled row compared.
    let json = dir.join("report.json");
    std::fs::write(&json, tensegrity_testbed::report::Report { scenarios: vec![r.clone()] }.to_json()).unwrap();
    if let Some(py) = crate::common::peer_python(&["pandas"], "table: the CSV read by pandas") {
        let script = format!(
            "import json, pandas\n\
             settled = json.load(open({json:?}))['scenarios'][0]['points'][0]['simulated']\n\
             t = pandas.read_csv({path:?})\n\
             row = t[t['tick'] == {tick}].iloc[0]\n\
             print(all(float(row['sim:' + q]) == v for q, v in settled.items()))",
            json = json.display().to_string(),
            path = path.display().to_string()
        );
        assert_eq!(peer_prints(&py, &script), "True", "pandas read other values");
        eprintln!("pandas read the settled row (tick {tick}) as the JSON report has it, bit for bit");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The folder `tensegrity run` of the prism and the icosahedron wrote `--table DIR/table` to
/// (each scenario's table beside it), the command having passed.
fn tables_of_two_scenarios(dir: &str, table: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("{dir}-{}", std::process::id()));
    let base = dir.join(table);
    let (code, out, err) = tensegrity(&[
        "run",
        "scenarios/custom/prism3.toml",
        "scenarios/custom/icosahedron6.toml",
        "--table",
        base.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    dir
}

/// The command line writes one table per scenario when it runs several.
#[test]
fn several_scenarios_get_one_table_each() {
    let dir = tables_of_two_scenarios("table-cli", "t.csv");
    for name in ["t-3-strut_tensegrity_prism.csv", "t-6-strut_tensegrity_icosahedron.csv"] {
        let (header, rows) = read_csv(&dir.join(name));
        assert!(header.iter().any(|h| h.starts_with("node:")) && !rows.is_empty(), "{name}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// With several scenarios and `--table FILE.arrow`, each scenario's table is an Arrow IPC file
/// named `FILE-<scenario>.arrow` (it was a CSV named `.csv`): arrow's reader opens both, each
/// with a node column and at least one row.
#[test]
fn several_scenarios_keep_the_arrow_format_of_the_tables_name() {
    let dir = tables_of_two_scenarios("table-cli-arrow", "t.arrow");
    for name in ["t-3-strut_tensegrity_prism.arrow", "t-6-strut_tensegrity_icosahedron.arrow"] {
        let file = std::fs::File::open(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let reader = arrow_ipc::reader::FileReader::try_new(file, None).expect("an Arrow IPC file");
        assert!(reader.schema().fields().iter().any(|f| f.name().starts_with("node:")), "{name}");
        let rows: usize = reader.map(|b| b.expect("a batch").num_rows()).sum();
        assert!(rows > 0, "{name}: no rows");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The same table as an Arrow IPC file (`--table FILE.arrow`): as many rows, `tick` UInt64 and
/// every other column Float64 with the CSV's exact values (read back with arrow's own reader);
/// pandas (with pyarrow) reads the settled row as the JSON report has it, bit for bit.
#[test]
fn the_trajectory_table_as_arrow_holds_the_csv_values() {
    use arrow_array::{Array, Float64Array, UInt64Array};
    let dir = std::env::temp_dir().join(format!("table-arrow-{}", std::process::id()));
    let (csv, arrow) = (dir.join("t.csv"), dir.join("t.arrow"));
    let sc = scenario::load(Path::new("scenarios/mohr2011/trajectory.toml")).unwrap();
    let r = run(&sc, &RunOptions { table: Some(csv.clone().into()), ..RunOptions::default() });
    let r2 = run(&sc, &RunOptions { table: Some(arrow.clone().into()), ..RunOptions::default() });
    assert_eq!(r.settle.steps, r2.settle.steps);
    let (header, rows) = read_csv(&csv);
    let reader = arrow_ipc::reader::FileReader::try_new(std::fs::File::open(&arrow).unwrap(), None).unwrap();
    let schema = reader.schema();
    let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
    assert_eq!(names, header.iter().map(String::as_str).collect::<Vec<_>>());
    let mut row = 0;
    for batch in reader {
        let batch = batch.unwrap();
        let ticks = batch.column(0).as_any().downcast_ref::<UInt64Array>().expect("tick is UInt64");
        for k in 0..batch.num_rows() {
            assert_eq!(ticks.value(k).to_string(), rows[row + k][0]);
            for c in 1..batch.num_columns() {
                let col = batch.column(c).as_any().downcast_ref::<Float64Array>().expect("Float64");
                let cell = &rows[row + k][c];
                if cell.is_empty() {
                    assert!(col.is_null(k), "{} at row {}", header[c], row + k);
                } else {
                    assert_eq!(col.value(k).to_bits(), cell.parse::<f64>().unwrap().to_bits(), "{}", header[c]);
                }
            }
        }
        row += batch.num_rows();
    }
    assert_eq!(row, rows.len());
    // pandas with pyarrow, where at hand.
    let settled = &r2.points[0].simulated;
    let json = dir.join("report.json");
    std::fs::write(&json, tensegrity_testbed::report::Report { scenarios: vec![r2.clone()] }.to_json()).unwrap();
    if let Some(py) = crate::common::peer_python(&["pandas", "pyarrow"], "table: the Arrow file read by pandas") {
        let script = format!(
            "import json, pandas\n\
             settled = json.load(open({json:?}))['scenarios'][0]['points'][0]['simulated']\n\
             t = pandas.read_feather({path:?})\n\
             rows = [r for _, r in t.iterrows() if all(float(r['sim:' + q]) == v for q, v in settled.items())]\n\
             print(len(rows) > 0)",
            json = json.display().to_string(),
            path = arrow.display().to_string()
        );
        assert_eq!(peer_prints(&py, &script), "True", "pandas read other values: {settled:?}");
        eprintln!("pandas read the Arrow table's settled row as the JSON report has it, bit for bit");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The table kept in memory (`TableTarget::Memory`, the Python package's) is the Arrow file's:
/// the same schema and the same record batches, value for value.
#[test]
fn the_table_in_memory_is_the_arrow_files() {
    use tensegrity_testbed::observers::table::{MemoryTable, TableTarget};
    let dir = std::env::temp_dir().join(format!("table-memory-{}", std::process::id()));
    let arrow = dir.join("t.arrow");
    let sc = scenario::load(Path::new("scenarios/custom/pinned_bar_sweep.toml")).unwrap();
    let kept = MemoryTable::default();
    run(&sc, &RunOptions { table: Some(arrow.clone().into()), ..RunOptions::default() });
    run(&sc, &RunOptions { table: Some(TableTarget::Memory(kept.clone())), ..RunOptions::default() });
    let (schema, batches) = kept.take().expect("the run handed its table over");
    let reader = arrow_ipc::reader::FileReader::try_new(std::fs::File::open(&arrow).unwrap(), None).unwrap();
    assert_eq!(reader.schema(), schema);
    let from_file: Vec<_> = reader.map(Result::unwrap).collect();
    assert!(!batches.is_empty());
    assert_eq!(from_file, batches);
    assert!(kept.take().is_none(), "handed over once");
    std::fs::remove_dir_all(&dir).ok();
}
