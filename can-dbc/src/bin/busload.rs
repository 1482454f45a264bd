//! Prints hand.dbc's worst-case bus load per message: `cargo run -p hand-dbc --bin busload`.

fn main() {
    print!("{}", hand_dbc::busload::format_table());
    let (_, total) = hand_dbc::busload::bus_load();
    if total > hand_dbc::busload::MAX_LOAD {
        eprintln!("bus load {:.2}% exceeds the 50% limit", total * 100.0);
        std::process::exit(1);
    }
}
