//! Admitting mazes: parsed (numeric or ASCII), made canonical (the numeric text),
//! solved (the optimum) and stored once by layout.

use super::{RegistryError, Result};
use crate::engine::mazefile::{self, numeric};
use crate::engine::{Maze, solver};
use crate::storage::Storage;
use crate::storage::mazes::{MazeRow, NewMaze};

/// Longest maze name.
pub const MAX_MAZE_NAME_CHARS: usize = 200;

/// Admits the maze in a file's `text` under `name`; its optimum is computed here.
///
/// # Errors
/// [`RegistryError::Invalid`] for a bad name or an invalid maze (with its line and
/// why), [`RegistryError::Conflict`] for a layout stored already, the database.
pub async fn admit(storage: &Storage, name: &str, text: &[u8], hidden: bool) -> Result<MazeRow> {
    if name.trim().is_empty() || name.chars().count() > MAX_MAZE_NAME_CHARS {
        return Err(RegistryError::Invalid(format!(
            "a maze needs a name of 1 to {MAX_MAZE_NAME_CHARS} characters"
        )));
    }
    if name.chars().any(char::is_control) {
        return Err(RegistryError::Invalid(
            "a maze's name may not hold control characters (they would act on the terminals that show it)"
                .into(),
        ));
    }
    let text = text.to_vec();
    let (maze, optimum) = super::bundles::blocking(move || {
        mazefile::parse(&text).map(|m| {
            let optimum = solver::solve(&m).map(|s| s.steps as i64);
            (m, optimum)
        })
    })
    .await?
    .map_err(|e| RegistryError::Invalid(format!("invalid maze: {e}")))?;
    insert(storage, name, &maze, hidden, optimum).await
}

/// Each of `mazes` (name and layout) as stored: the stored maze of its layout, or the
/// maze admitted as a public maze under its name (the first of a layout given twice
/// names it); `None` (nothing stored) when its goal room cannot be reached. The mazes
/// are solved on every core and stored in one transaction.
///
/// # Errors
/// The database.
pub async fn find_or_admit_all(
    storage: &Storage,
    mazes: Vec<(String, Maze)>,
) -> Result<Vec<Option<MazeRow>>> {
    let (mazes, optima) = super::bundles::blocking(move || {
        let optima = optima(&mazes);
        (mazes, optima)
    })
    .await?;
    let hashes: Vec<String> = mazes.iter().map(|(_, m)| m.hash()).collect();
    let layouts: Vec<String> = mazes.iter().map(|(_, m)| numeric::write(m)).collect();
    let new: Vec<NewMaze> = (0..mazes.len())
        .filter_map(|i| {
            optima[i].map(|optimum| NewMaze {
                name: &mazes[i].0,
                hash: &hashes[i],
                dim: mazes[i].1.dim() as i64,
                layout: &layouts[i],
                hidden: false,
                optimum: Some(optimum),
            })
        })
        .collect();
    let mut stored = storage.find_or_insert_mazes(&new).await?.into_iter();
    Ok(optima
        .iter()
        .map(|o| o.and_then(|_| stored.next()))
        .collect())
}

/// The optimum of each maze (`None`: its goal cannot be reached), the mazes shared
/// out over the cores.
fn optima(mazes: &[(String, Maze)]) -> Vec<Option<i64>> {
    let per_thread = mazes
        .len()
        .div_ceil(crate::runner::affinity::cores())
        .max(1);
    std::thread::scope(|scope| {
        let parts: Vec<_> = mazes
            .chunks(per_thread)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|(_, m)| solver::solve(m).map(|s| s.steps as i64))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        parts
            .into_iter()
            .flat_map(|p| p.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

async fn insert(
    storage: &Storage,
    name: &str,
    maze: &Maze,
    hidden: bool,
    optimum: Option<i64>,
) -> Result<MazeRow> {
    Ok(storage
        .insert_maze(&NewMaze {
            name,
            hash: &maze.hash(),
            dim: maze.dim() as i64,
            layout: &numeric::write(maze),
            hidden,
            optimum,
        })
        .await?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support;

    #[tokio::test]
    async fn mazes_are_admitted_once_by_layout() {
        let (db, _d) = test_support::fresh().await;
        let maze = test_support::maze();
        let text = numeric::write(&maze);
        let row = admit(&db, "m", text.as_bytes(), true).await.unwrap();
        assert!(row.hidden && row.optimum.is_some());
        let err = admit(&db, "again", text.as_bytes(), false)
            .await
            .unwrap_err();
        assert!(matches!(err, RegistryError::Conflict(_)), "{err}");
        // Found by layout, not stored twice; a maze whose goal cannot be reached is not
        // stored; a new one is stored under the first of its names.
        let closed = numeric::parse(b"4\n0,0,0,0\n0,0,0,0\n0,0,0,0\n0,0,0,0\n").unwrap();
        let open = crate::engine::generator::generate(12, 7).unwrap();
        let found = find_or_admit_all(
            &db,
            vec![
                ("x".into(), maze.clone()),
                ("closed".into(), closed),
                ("open".into(), open.clone()),
                ("open again".into(), open),
            ],
        )
        .await
        .unwrap();
        assert_eq!(found[0].as_ref().unwrap().maze_id, row.maze_id);
        assert_eq!(found[0].as_ref().unwrap().name, "m");
        assert!(found[1].is_none());
        let new = found[2].as_ref().unwrap();
        assert_eq!((new.name.as_str(), new.hidden), ("open", false));
        assert!(new.optimum.is_some());
        assert_eq!(found[3].as_ref(), Some(new));
        assert_eq!(db.count_mazes().await.unwrap(), 2);

        let err = admit(&db, "bad", b"12\n1,2\n", false).await.unwrap_err();
        assert!(err.to_string().starts_with("invalid maze: "), "{err}");
        assert!(err.is_client_error());
        let err = admit(&db, " ", text.as_bytes(), false).await.unwrap_err();
        assert!(matches!(err, RegistryError::Invalid(_)), "{err}");
    }
}
