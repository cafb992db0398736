//! Mazes: canonical layout, hash, visibility and optimum.

use sqlx::FromRow;

use super::{Result, Storage, StorageError, is_unique_violation, now_ms};

/// A stored maze.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct MazeRow {
    /// Id.
    pub maze_id: i64,
    /// Display name.
    pub name: String,
    /// SHA-256 of the canonical numeric text.
    pub hash: String,
    /// Side.
    pub dim: i64,
    /// Canonical numeric text.
    pub layout: String,
    /// Hidden (ranking) maze.
    #[sqlx(try_from = "super::Flag")]
    pub hidden: bool,
    /// Fewest run-1 steps, if the goal is reachable.
    pub optimum: Option<i64>,
    /// When it was stored (unix ms).
    pub created_at: i64,
}

/// A maze to store.
#[derive(Debug, Clone)]
pub struct NewMaze<'a> {
    /// Display name.
    pub name: &'a str,
    /// SHA-256 of the canonical numeric text.
    pub hash: &'a str,
    /// Side.
    pub dim: i64,
    /// Canonical numeric text.
    pub layout: &'a str,
    /// Hidden (ranking) maze.
    pub hidden: bool,
    /// Fewest run-1 steps.
    pub optimum: Option<i64>,
}

impl Storage {
    /// Stores a maze.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] naming the existing maze when the same layout is stored.
    pub async fn insert_maze(&self, m: &NewMaze<'_>) -> Result<MazeRow> {
        let inserted = sqlx::query_as(
            "insert into maze (name, hash, dim, layout, hidden, optimum, created_at)
             values ($1, $2, $3, $4, $5, $6, $7) returning *",
        )
        .bind(m.name)
        .bind(m.hash)
        .bind(m.dim)
        .bind(m.layout)
        .bind(i64::from(m.hidden))
        .bind(m.optimum)
        .bind(now_ms())
        .fetch_one(self.pool())
        .await;
        match inserted {
            Ok(row) => Ok(row),
            Err(e) if is_unique_violation(&e) => {
                let existing = self.get_maze_by_hash(m.hash).await?;
                Err(StorageError::Conflict(match existing {
                    Some(x) => format!(
                        "the same maze is stored already as maze {} ({:?})",
                        x.maze_id, x.name
                    ),
                    None => "the same maze is stored already".to_string(),
                }))
            }
            Err(e) => Err(e.into()),
        }
    }

    /// A maze by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_maze(&self, maze_id: i64) -> Result<Option<MazeRow>> {
        Ok(sqlx::query_as("select * from maze where maze_id = $1")
            .bind(maze_id)
            .fetch_optional(self.pool())
            .await?)
    }

    /// A maze by content hash.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_maze_by_hash(&self, hash: &str) -> Result<Option<MazeRow>> {
        Ok(sqlx::query_as("select * from maze where hash = $1")
            .bind(hash)
            .fetch_optional(self.pool())
            .await?)
    }

    /// Every maze, by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_mazes(&self) -> Result<Vec<MazeRow>> {
        Ok(sqlx::query_as("select * from maze order by maze_id")
            .fetch_all(self.pool())
            .await?)
    }

    /// The number of stored mazes.
    ///
    /// # Errors
    /// Database failures.
    pub async fn count_mazes(&self) -> Result<i64> {
        Ok(sqlx::query_scalar("select count(*) from maze")
            .fetch_one(self.pool())
            .await?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn duplicate_layouts_are_refused_naming_the_first() {
        for (db, _guard) in backends().await {
            let m = NewMaze {
                name: "one",
                hash: "h",
                dim: 2,
                layout: "2\n3,6\n9,12\n",
                hidden: true,
                optimum: Some(1),
            };
            let row = db.insert_maze(&m).await.unwrap();
            assert!(row.hidden);
            let again = db
                .insert_maze(&NewMaze {
                    name: "two",
                    ..m.clone()
                })
                .await;
            match again {
                Err(StorageError::Conflict(msg)) => {
                    assert!(msg.contains(&format!("maze {}", row.maze_id)))
                }
                other => panic!("{other:?}"),
            }
            assert_eq!(db.count_mazes().await.unwrap(), 1);
            assert_eq!(
                db.get_maze(row.maze_id).await.unwrap().unwrap().layout,
                m.layout
            );
        }
    }
}
