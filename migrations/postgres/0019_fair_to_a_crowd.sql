-- mazearena schema, version 19 (PostgreSQL): fair to a crowd. Budgets of what proves nothing
-- (wrong keys, wrong invite codes, anonymous registrations) counted per client address
-- in the database, so that every API server of a database spends the same budget; the
-- limits a single match plays under; the build time each version spent. Never edit an
-- applied migration: add a new file.

-- A budget of tries (GCRA): `tat` is the theoretical arrival time (unix ms) of the
-- next try. A try at `now` is allowed while max(tat, now) + interval - now stays within
-- the burst; it then moves `tat` on by one interval. `budget` names what is counted
-- and whose it is: `wrong_key:ADDRESS`, `registration:ADDRESS`, `invite:CODE_HASH`.
-- Rows whose `tat` has passed hold nothing and are removed hourly.
create table rate_budget (
    budget text primary key,
    tat bigint not null
);

-- The limits a single match plays under (JSON, as `tournament.limits`): a practice
-- match on a competition's practice maze plays under that competition's limits.
alter table match add column limits text;

-- How long the version's build and validation match took (ms, wall-clock time on the
-- builder): spent from its owner's daily build time, whatever the outcome.
alter table bot_version add column build_ms bigint;
