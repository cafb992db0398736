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

/// The start of a maze insert; `values` and its rows follow, 7 parameters a row.
const INSERT: &str =
    "insert into maze (name, hash, dim, layout, hidden, optimum, created_at) values";

/// `query` with `m`'s 7 values bound next, as stored at `now`.
fn bind<'q>(
    query: sqlx::query::QueryAs<'q, sqlx::Any, MazeRow, sqlx::any::AnyArguments<'q>>,
    m: &NewMaze<'q>,
    now: i64,
) -> sqlx::query::QueryAs<'q, sqlx::Any, MazeRow, sqlx::any::AnyArguments<'q>> {
    query
        .bind(m.name)
        .bind(m.hash)
        .bind(m.dim)
        .bind(m.layout)
        .bind(i64::from(m.hidden))
        .bind(m.optimum)
        .bind(now)
}

impl Storage {
    /// Stores a maze.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] naming the existing maze when the same layout is stored.
    pub async fn insert_maze(&self, m: &NewMaze<'_>) -> Result<MazeRow> {
        let sql = format!("{INSERT} {} returning *", super::placeholders(1, 7));
        let inserted = bind(sqlx::query_as(&sql), m, now_ms())
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

    /// Stores each of `mazes` whose layout is not stored yet (the first of a layout
    /// given twice names it) and returns the stored row of each, in order: many mazes
    /// in a few statements of one transaction.
    ///
    /// # Errors
    /// Database failures.
    pub async fn find_or_insert_mazes(&self, mazes: &[NewMaze<'_>]) -> Result<Vec<MazeRow>> {
        /// Mazes a lookup (1 parameter each) carries.
        const ROWS_PER_LOOKUP: usize = 500;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        for chunk in mazes.chunks(super::ROWS_PER_INSERT) {
            let sql = format!(
                "{INSERT} {} on conflict (hash) do nothing",
                super::placeholders(chunk.len(), 7)
            );
            let mut query = sqlx::query_as::<_, MazeRow>(&sql);
            for m in chunk {
                query = bind(query, m, now);
            }
            // The rows, new and old, are read once below.
            query.fetch_all(&mut *tx).await?;
        }
        let mut stored = std::collections::HashMap::new();
        for chunk in mazes.chunks(ROWS_PER_LOOKUP) {
            let sql = format!(
                "select * from maze where hash in {}",
                super::placeholders(1, chunk.len())
            );
            let mut query = sqlx::query_as::<_, MazeRow>(&sql);
            for m in chunk {
                query = query.bind(m.hash);
            }
            for row in query.fetch_all(&mut *tx).await? {
                stored.insert(row.hash.clone(), row);
            }
        }
        tx.commit().await?;
        mazes
            .iter()
            .map(|m| {
                // Only a maze deleted meanwhile can be missing.
                stored
                    .get(m.hash)
                    .cloned()
                    .ok_or(StorageError::Database(sqlx::Error::RowNotFound))
            })
            .collect()
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

    #[tokio::test]
    async fn many_mazes_are_stored_once_each_in_order() {
        for (db, _guard) in backends().await {
            let old = db
                .insert_maze(&NewMaze {
                    name: "stored before",
                    hash: "h1",
                    dim: 2,
                    layout: "2\n3,6\n9,12\n",
                    hidden: true,
                    optimum: Some(1),
                })
                .await
                .unwrap();
            // 450 mazes: more than one statement's worth; h1 is stored already, and
            // h7 is given twice.
            let hashes: Vec<String> = (0..450).map(|i| format!("h{i}")).collect();
            let names: Vec<String> = (0..450).map(|i| format!("m{i}")).collect();
            let mut given: Vec<NewMaze> = (0..450)
                .map(|i| NewMaze {
                    name: &names[i],
                    hash: &hashes[i],
                    dim: 2,
                    layout: "2\n3,6\n9,12\n",
                    hidden: false,
                    optimum: Some(i as i64),
                })
                .collect();
            given.push(NewMaze {
                name: "second h7",
                ..given[7].clone()
            });
            let rows = db.find_or_insert_mazes(&given).await.unwrap();
            assert_eq!(rows.len(), given.len());
            for (row, m) in rows.iter().zip(&given) {
                assert_eq!(row.hash, m.hash);
            }
            assert_eq!(rows[1], old, "a stored maze is found, not changed");
            assert_eq!(rows[7].name, "m7", "the first of a layout names it");
            assert_eq!(rows[450].maze_id, rows[7].maze_id);
            assert_eq!(rows[300].optimum, Some(300));
            assert!(!rows[300].hidden);
            assert_eq!(db.count_mazes().await.unwrap(), 450);
            // Stored in the order given.
            assert!(rows[2].maze_id < rows[3].maze_id && rows[3].maze_id < rows[449].maze_id);
        }
    }
}
