//! Report tables as polars DataFrames: written next to the report as CSV and Parquet (readable by
//! polars, pandas and h5py-side tooling alike) and rendered into the Markdown.

use polars::prelude::*;
use std::path::Path;

/// A CSV file with a header row.
pub fn read_csv(path: &Path) -> PolarsResult<DataFrame> {
    CsvReadOptions::default().with_has_header(true).try_into_reader_with_file_path(Some(path.to_path_buf()))?.finish()
}

/// Column `name` of `df` as floats (NaN where missing).
pub fn floats(df: &DataFrame, name: &str) -> PolarsResult<Vec<f64>> {
    Ok(df.column(name)?.cast(&DataType::Float64)?.f64()?.into_iter().map(|v| v.unwrap_or(f64::NAN)).collect())
}

/// A DataFrame of `columns`.
pub fn frame(columns: Vec<Column>) -> PolarsResult<DataFrame> {
    DataFrame::new(columns)
}

/// A float column.
pub fn col(name: &str, values: Vec<f64>) -> Column {
    Column::new(name.into(), values)
}

/// A string column.
pub fn scol(name: &str, values: Vec<String>) -> Column {
    Column::new(name.into(), values)
}

/// An unsigned integer column.
pub fn ucol(name: &str, values: Vec<u64>) -> Column {
    Column::new(name.into(), values)
}

/// Same concentration (the scenes store 0.563 … 4.5 exactly as the paper prints them).
pub fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs()
}

/// Writes `df` as `<dir>/<stem>.csv` and `<dir>/<stem>.parquet`.
pub fn write(df: &mut DataFrame, dir: &Path, stem: &str) -> PolarsResult<()> {
    std::fs::create_dir_all(dir)?;
    CsvWriter::new(&mut std::fs::File::create(dir.join(format!("{stem}.csv")))?).finish(df)?;
    ParquetWriter::new(std::fs::File::create(dir.join(format!("{stem}.parquet")))?).finish(df)?;
    Ok(())
}

fn cell(value: AnyValue, digits: usize) -> String {
    match value {
        AnyValue::Null => "–".into(),
        AnyValue::Float64(v) if v.is_nan() => "–".into(),
        AnyValue::Float64(v) => format!("{v:.digits$}"),
        AnyValue::Float32(v) => format!("{v:.digits$}"),
        AnyValue::String(s) => s.to_string(),
        AnyValue::StringOwned(s) => s.to_string(),
        other => other.to_string(),
    }
}

/// A Markdown table of `df` with `headers` for its columns (in order); the floats of column k
/// get `digits[k]` decimals.
pub fn markdown(df: &DataFrame, headers: &[&str], digits: &[usize]) -> PolarsResult<String> {
    let columns = df.get_columns();
    if headers.len() != columns.len() || digits.len() != columns.len() {
        polars_bail!(ShapeMismatch: "{} headers and {} digit counts for {} columns", headers.len(), digits.len(), columns.len());
    }
    let mut out = format!("| {} |\n|{}\n", headers.join(" | "), "---|".repeat(headers.len()));
    for row in 0..df.height() {
        let cells: Vec<String> =
            columns.iter().zip(digits).map(|(c, &d)| c.get(row).map(|v| cell(v, d))).collect::<PolarsResult<_>>()?;
        out += &format!("| {} |\n", cells.join(" | "));
    }
    Ok(out)
}
