//! champion: plays for the score, run-1 steps + run-0 steps / 30.
//! The strategy is in [`mazebot::champion`]; `--unknown-weight`, `--likely-weight`,
//! and `--gain-weight` override its weights for
//! experiments. `--no-debug` sends no debug drawings (they never change the moves).

use mazebot::champion::{Champion, Params};
use mazebot::protocol;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<f64>().ok())
    };
    let milli = |w: f64| (w * 1000.0) as u64;
    let defaults = Params::default();
    let champion = Champion::new(Params {
        unknown_milli: arg("--unknown-weight").map_or(defaults.unknown_milli, milli),
        likely_weight: arg("--likely-weight").unwrap_or(defaults.likely_weight),
        gain_weight: arg("--gain-weight").unwrap_or(defaults.gain_weight),
        tie_jitter: None,
    });
    if args.iter().any(|a| a == "--no-debug") {
        protocol::run(champion.without_debug());
    } else {
        protocol::run(champion);
    }
}
