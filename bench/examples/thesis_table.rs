//! Prints the thesis experiment table (docs/estimator.md).
fn main() {
    match bench::thesis::table() {
        Ok(rows) => println!("{}", bench::thesis::markdown(&rows)),
        Err(e) => eprintln!("error: {e}"),
    }
}
