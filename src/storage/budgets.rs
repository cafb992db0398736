//! Budgets of tries counted in the database, so that every API server of one database
//! spends the same budget: a try of budget `name` is allowed or refused in one
//! statement (the generic cell rate algorithm: `tries` in any `period`, coming back one
//! every `period / tries`). Table `rate_budget`; what each budget counts is the
//! caller's (`api::limits`).

use super::{Result, Storage};

/// How many tries a budget allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rate {
    /// Tries in any `period_ms` (at least 1).
    pub tries: u32,
    /// The period (ms).
    pub period_ms: i64,
}

impl Rate {
    /// `tries` an hour.
    pub fn per_hour(tries: u32) -> Rate {
        Rate {
            tries: tries.max(1),
            period_ms: 3_600_000,
        }
    }

    /// The time one try takes to come back (ms, at least 1).
    fn interval_ms(self) -> i64 {
        (self.period_ms / i64::from(self.tries.max(1))).max(1)
    }

    /// How far ahead of now the budget's next-try time may run.
    fn burst_ms(self) -> i64 {
        self.interval_ms() * i64::from(self.tries.max(1))
    }
}

impl Storage {
    /// Spends one try of budget `name` at `now` (unix ms): `Ok(())`, or the time (ms)
    /// until a try is allowed again, spending nothing.
    ///
    /// # Errors
    /// Database failures.
    pub async fn spend_budget(
        &self,
        name: &str,
        rate: Rate,
        now: i64,
    ) -> Result<std::result::Result<(), i64>> {
        let interval = rate.interval_ms();
        let burst = rate.burst_ms();
        let _turn = self.write_turn().await;
        let spent: Option<i64> = sqlx::query_scalar(
            "insert into rate_budget (budget, tat) values ($1, $2 + $3)
             on conflict (budget) do update
                 set tat = (case when rate_budget.tat > $2 then rate_budget.tat else $2 end) + $3
                 where (case when rate_budget.tat > $2 then rate_budget.tat else $2 end) + $3 - $2 <= $4
             returning tat",
        )
        .bind(name)
        .bind(now)
        .bind(interval)
        .bind(burst)
        .fetch_optional(self.pool())
        .await?;
        if spent.is_some() {
            return Ok(Ok(()));
        }
        let tat: Option<i64> = sqlx::query_scalar("select tat from rate_budget where budget = $1")
            .bind(name)
            .fetch_optional(self.pool())
            .await?;
        Ok(Err(tat.map_or(interval, |tat| {
            (tat + interval - burst - now).max(1)
        })))
    }

    /// Removes the budgets that hold nothing at `now` (every try has come back); how
    /// many.
    ///
    /// # Errors
    /// Database failures.
    pub async fn prune_budgets(&self, now: i64) -> Result<u64> {
        let _turn = self.write_turn().await;
        Ok(sqlx::query("delete from rate_budget where tat <= $1")
            .bind(now)
            .execute(self.pool())
            .await?
            .rows_affected())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn a_budget_allows_its_tries_then_refuses_until_one_comes_back() {
        for (db, _guard) in backends().await {
            let rate = Rate {
                tries: 3,
                period_ms: 3_000,
            };
            let t0 = 1_000_000;
            for _ in 0..3 {
                assert_eq!(db.spend_budget("a", rate, t0).await.unwrap(), Ok(()));
            }
            // The fourth at once is refused, for one interval (1 s), and spends nothing.
            assert_eq!(db.spend_budget("a", rate, t0).await.unwrap(), Err(1_000));
            assert_eq!(
                db.spend_budget("a", rate, t0 + 400).await.unwrap(),
                Err(600)
            );
            // Another budget is untouched.
            assert_eq!(db.spend_budget("b", rate, t0).await.unwrap(), Ok(()));
            // One try has come back after one interval; only one.
            assert_eq!(
                db.spend_budget("a", rate, t0 + 1_000).await.unwrap(),
                Ok(())
            );
            assert!(
                db.spend_budget("a", rate, t0 + 1_000)
                    .await
                    .unwrap()
                    .is_err()
            );
            // After the whole period, the whole budget.
            for _ in 0..3 {
                assert_eq!(
                    db.spend_budget("a", rate, t0 + 5_000).await.unwrap(),
                    Ok(())
                );
            }
            // Pruning removes only the budgets whose tries have all come back.
            assert_eq!(db.prune_budgets(t0 + 5_000).await.unwrap(), 1, "b");
            assert!(
                db.spend_budget("a", rate, t0 + 5_000)
                    .await
                    .unwrap()
                    .is_err()
            );
        }
    }
}
