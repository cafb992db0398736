-- How many times a version's build has been claimed: a build whose worker died while it
-- ran is claimed again after its lease, at most a few times (MAX_BUILD_ATTEMPTS), then
-- recorded as build_failed with the reason, as matches are.
alter table bot_version add column build_attempts integer not null default 0;
