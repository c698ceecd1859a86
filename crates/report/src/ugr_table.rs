//! `report ugr-table FILE.ies|ldt`: the CIE 190 tabular UGR of a luminaire
//! (`luxest_photometry::ugr_table`), printed as the standard table (the reference room 4H × 8H,
//! 70/50/20, in brackets) and, with `-o`, written as CSV (`x_h,y_h,ceiling,walls,floor,
//! crosswise,endwise`) or text (`.txt`).

use luxest_io::outputs::OutputPlan;
use luxest_io::{Error, Result};
use std::path::PathBuf;

/// The UGR table of a luminaire file (CIE 190 tabular method).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The photometric file (.ies or .ldt).
    pub file: PathBuf,
    /// Write the table to this file too: `.csv` (one row per room and reflectances) or `.txt`.
    #[arg(short, long)]
    pub out: Option<PathBuf>,
}

/// Runs `report ugr-table`.
pub fn run(args: Args) -> Result<()> {
    if let Some(out) = &args.out {
        let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !matches!(ext, "csv" | "txt") {
            return Err(Error::Usage(format!(
                "--out {}: the table is written as .csv or .txt",
                out.display()
            )));
        }
    }
    let p = luxest_photometry::load(&args.file).map_err(|e| match e.line {
        Some(line) => Error::at(&e.file, format!("line {line}"), e.message),
        None => Error::input(&e.file, e.message),
    })?;
    let table = luxest_photometry::ugr_table(&p).map_err(|m| Error::input(&args.file, m))?;
    let text = table.to_text();
    if let Some(out) = &args.out {
        let mut plan =
            OutputPlan::new(std::slice::from_ref(&args.file), std::slice::from_ref(out))?;
        let body = if out.extension().is_some_and(|e| e == "csv") {
            table.to_csv()
        } else {
            text.clone()
        };
        plan.write_bytes(out, body.as_bytes())?;
        plan.commit()?;
    }
    print!("{text}");
    Ok(())
}
