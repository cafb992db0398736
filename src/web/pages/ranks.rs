//! The cells every standings table shares: a rank with the range its interval allows,
//! the 95% interval of the mean score, the tie group, and the note that states the
//! rules ([`crate::ranking`]).

use maud::{Markup, html};

use crate::ranking::Uncertainty;

/// The rank, and in brackets the range the intervals allow when it is wider.
pub(super) fn rank_cell(rank: i64, u: &Uncertainty) -> Markup {
    html! {
        td.num.rank title={ "ranks " (u.rank_range) " are possible within the 95% intervals" } {
            (rank)
            @if u.rank_best != u.rank_worst { span.muted.rank-range { " (" (u.rank_range) ")" } }
        }
    }
}

/// The interval of the mean score (a dash when it is withheld over hidden matches).
pub(super) fn interval_cell(u: &Uncertainty) -> Markup {
    html! {
        @if u.withheld {
            td.num.interval.wide title="not shown over hidden matches: it would tell single matches" { "-" }
        } @else {
            td.num.interval.wide { (format!("{:.3}–{:.3}", u.low, u.high)) }
        }
    }
}

/// The tie group when another bot shares it.
pub(super) fn tie_cell(u: &Uncertainty) -> Markup {
    html! {
        td.tie.wide {
            @if u.tied { span title="not significantly different from the group's first bot" { "tied (group " (u.tie_group) ")" } }
        }
    }
}

/// The header cells of [`interval_cell`] and [`tie_cell`].
pub(super) fn header_cells() -> Markup {
    html! {
        th.num.wide title="95% interval of the mean score: a bootstrap over each maze's seeds" { "95% interval" }
        th.wide { "tie" }
    }
}

/// The rules under a table: the order, the tie-break, what the interval and the tie
/// groups mean; and a warning when a bot has a single run on a maze.
pub(super) fn ranking_note<'a>(runs_per_maze: impl IntoIterator<Item = &'a Uncertainty>) -> Markup {
    let lines: Vec<&Uncertainty> = runs_per_maze.into_iter().collect();
    let single = lines.iter().any(|u| u.runs_per_maze == 1);
    let withheld = lines.iter().any(|u| u.withheld);
    html! {
        p.muted.ranking-note {
            "Lower mean score ranks first; equal means share a rank and are listed by name. "
            "The interval is the 95% range of the mean over the luck of the seeds (a bootstrap that keeps the mazes "
            "and resamples each maze's runs, with a fixed seed: the same matches always give the same table). "
            "A rank in brackets is the range those intervals allow. Bots marked tied are not significantly "
            "different from their group's first bot (a paired test on the mazes and seeds both played)."
            @if single {
                " Some bots have one run on a maze: the luck of a randomized bot is not measured there (play more seeds per maze)."
            }
            @if withheld {
                " Over hidden mazes no interval, rank range or tie group is shown but what the means say: with few hidden matches they would tell each match's score."
            }
        }
    }
}
