-- mazearena schema, version 3: bot versions built on the server, and environment
-- variables declared for a bot. Never edit an applied migration: add a new file.

-- the build command run once in the version's folder, in the sandbox, before it plays;
-- null when the version needs no build
alter table bot_version add column build_command text;
-- ready (plays), building (waiting for or in its build), build_failed (never plays)
alter table bot_version add column build_status text not null default 'ready';
-- the end of the build's output (stdout and stderr), for the owner
alter table bot_version add column build_log text;
-- when the build ended (unix ms)
alter table bot_version add column built_at integer;
-- environment variables declared for the bot: a JSON object of strings
alter table bot_version add column env text not null default '{}';

create index bot_version_build on bot_version (build_status);
