//! The `crane` command line (placeholder; see issues 4-6).
fn main() {
    println!("crane: no subcommand yet");
}
