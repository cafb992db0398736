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

/// The stored maze with `maze`'s layout, or `maze` admitted as a public maze named
/// `name`; `None` (nothing stored) when its goal room cannot be reached.
///
/// # Errors
/// The database.
pub async fn find_or_admit(storage: &Storage, name: &str, maze: &Maze) -> Result<Option<MazeRow>> {
    let Some(optimum) = solver::solve(maze).map(|s| s.steps as i64) else {
        return Ok(None);
    };
    if let Some(row) = storage.get_maze_by_hash(&maze.hash()).await? {
        return Ok(Some(row));
    }
    match insert(storage, name, maze, false, Some(optimum)).await {
        Ok(row) => Ok(Some(row)),
        // Stored meanwhile by another process sharing the database.
        Err(RegistryError::Conflict(_)) => Ok(storage.get_maze_by_hash(&maze.hash()).await?),
        Err(e) => Err(e),
    }
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
        let found = find_or_admit(&db, "x", &maze).await.unwrap().unwrap();
        assert_eq!(found.maze_id, row.maze_id);

        let err = admit(&db, "bad", b"12\n1,2\n", false).await.unwrap_err();
        assert!(err.to_string().starts_with("invalid maze: "), "{err}");
        assert!(err.is_client_error());
        let err = admit(&db, " ", text.as_bytes(), false).await.unwrap_err();
        assert!(matches!(err, RegistryError::Invalid(_)), "{err}");
    }
}
