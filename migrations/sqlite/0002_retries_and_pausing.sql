-- mazearena schema, version 2: a retry limit on matches whose server died, and paused
-- bots. Never edit an applied migration: add a new file.
--
-- match.status now also takes `memory_limit`, `process_limit`, `scratch_limit` (the bot
-- went over one of the match's limits) and `aborted` (the match was running each time
-- its server died, more often than it is retried; or its bot was paused before it
-- ran). The whole list: queued, running, finished, step_limit, timeout, crashed,
-- protocol_error, memory_limit, process_limit, scratch_limit, aborted.

-- how many times the match's lease expired while it ran (its server died); a graceful
-- shutdown that puts it back in the queue does not count. Past MAX_MATCH_RETRIES the
-- match is recorded as aborted.
alter table match add column lease_expiries integer not null default 0;

-- why the bot is paused (its matches keep aborting); null while it is not paused
alter table bot add column paused_reason text;
-- when it was paused (unix ms); null while it is not paused
alter table bot add column paused_at integer;
-- when it was last resumed (unix ms), by an admin or by a new version: matches aborted
-- before then no longer count towards pausing it
alter table bot add column resumed_at integer;
