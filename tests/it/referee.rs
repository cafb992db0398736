//! Referee checks whose expected values come from RULES.md, on the classic mazes.

use mazearena::engine::game::{Action, Game, GameConfig, StepEvent};
use mazearena::engine::{Heading, Position, solver};

use crate::support::classic;

#[test]
fn the_start_reading_of_test_maze_01_is_0_11_0() {
    let mut game = Game::new(classic(1), GameConfig::default());
    let sense = game.begin_step().unwrap();
    assert_eq!((sense.run, sense.step), (0, 1));
    assert_eq!(sense.sensors, [0, 11, 0]);
}

#[test]
fn the_solver_gives_17_22_25_on_the_classic_mazes() {
    // RULES.md "Reference figures".
    for (n, want) in [(1, 17), (2, 22), (3, 25)] {
        let solution = solver::solve(&classic(n)).unwrap();
        assert_eq!(solution.steps, want, "test_maze_0{n}");
        assert_eq!(solution.actions.len() as u32, want);
    }
}

#[test]
fn the_solvers_actions_replayed_by_the_referee_reach_the_goal_in_that_many_steps() {
    for n in 1..=3 {
        let maze = classic(n);
        let solution = solver::solve(&maze).unwrap();
        let mut game = Game::new(maze, GameConfig::default());
        // Run 0 the same way, then reset and replay for run 1.
        for action in solution
            .actions
            .iter()
            .chain([&Action::RESET])
            .chain(&solution.actions)
        {
            game.begin_step().unwrap();
            game.apply(*action);
        }
        let score = game.score().expect("finished");
        assert_eq!(score.run1_steps, solution.steps);
        assert_eq!(score.run0_steps, solution.steps + 1);
    }
}

#[test]
fn no_shorter_run_exists_than_the_solver_says() {
    // An independent check of minimality on maze 01: breadth-first over the referee
    // itself (clones of the game), not over the solver's own model.
    let maze = classic(1);
    let mut frontier = vec![Game::new(maze, GameConfig::default())];
    let mut seen = std::collections::HashSet::new();
    for depth in 1..=16 {
        let mut next = Vec::new();
        for g in &frontier {
            for rotation in [-90, 0, 90] {
                for movement in -3..=3 {
                    let mut g2 = g.clone();
                    g2.begin_step().unwrap();
                    let r = g2.apply(Action::turn_move(rotation, movement));
                    assert!(
                        !g2.maze().is_goal(r.position),
                        "goal reached in {depth} steps, fewer than 17"
                    );
                    if seen.insert((r.position, r.heading)) {
                        next.push(g2);
                    }
                }
            }
        }
        frontier = next;
    }
}

#[test]
fn a_wall_stops_the_robot_on_maze_01() {
    let mut game = Game::new(classic(1), GameConfig::default());
    // At the start the right sensor reads 0: turning right and moving is blocked.
    game.begin_step().unwrap();
    let r = game.apply(Action::turn_move(90, 2));
    assert_eq!(r.position, Position::new(0, 0));
    assert_eq!(r.heading, Heading::Right);
    assert!(r.blocked);
    assert_eq!(r.event, StepEvent::Move);
    // Facing right at (0,0) of maze 01, the sensors read [11, 0, 0].
    assert_eq!(game.begin_step().unwrap().sensors, [11, 0, 0]);
}
