//! A table `figures` reads is its raw rows' (issue 77's re-probe): one edited in any column, a
//! cell's line duplicated or dropped, is refused naming the table, the cell and the column.

use super::*;

#[test]
fn a_table_that_is_not_its_rows_is_refused_naming_the_cell_and_column() {
    let exp = Experiment::load(Path::new("experiments/rooms.toml"), None).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let results = tmp.path();
    for cell in &exp.cells {
        let (from, to) = (
            exp.cell_dir(Path::new("results"), cell),
            exp.cell_dir(results, cell),
        );
        std::fs::create_dir_all(&to).unwrap();
        for entry in std::fs::read_dir(&from).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
        }
    }
    let table = pbcs::tables::table_path(results, exp.name);
    std::fs::create_dir_all(table.parent().unwrap()).unwrap();
    std::fs::copy(
        pbcs::tables::table_path(Path::new("results"), exp.name),
        &table,
    )
    .unwrap();
    let check = || {
        let stats = pbcs::tables::read_table(&table)?;
        pbcs::tables::check_against_rows(&exp, results, &stats)
    };
    check().unwrap();
    let text = std::fs::read_to_string(&table).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let first = &lines[1];
    let cell = exp.cells[0].id.to_string();
    assert!(first.contains(&cell), "{first}");
    let edited = |column: &str, to: &str| {
        let header: Vec<&str> = lines[0].split(',').collect();
        let k = header.iter().position(|h| *h == column).unwrap();
        let mut fields: Vec<String> = first.split(',').map(String::from).collect();
        fields[k] = to.to_string();
        text.replacen(first, &fields.join(","), 1)
    };
    let duplicated = text.replacen(first, &format!("{first}\n{first}"), 1);
    let dropped = text.replacen(&format!("{first}\n"), "", 1);
    for (edit, needles) in [
        (
            edited("steps_median", "1"),
            vec!["line 2", cell.as_str(), "steps_median"],
        ),
        (edited("label", "Not its label"), vec!["line 2", "label"]),
        (duplicated, vec!["line 3"]),
        // Not a value of its column: named by its name (before: "field 6").
        (
            edited("successes", "-1"),
            vec!["line 2", "column `successes`"],
        ),
        (
            edited("steps_median", "abc"),
            vec!["line 2", "column `steps_median`"],
        ),
        (dropped, vec!["line 2"]),
    ] {
        std::fs::write(&table, &edit).unwrap();
        let err = check().unwrap_err().to_string();
        assert!(err.contains("rooms.csv"), "{err}");
        for n in needles {
            assert!(err.contains(n), "{n}: {err}");
        }
    }
}
