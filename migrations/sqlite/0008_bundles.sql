-- mazearena schema, version 8: bot files in the database, and builds claimed with a
-- lease by the workers. Never edit an applied migration: add a new file.

-- A bot's files, content-addressed: the canonical .tar.gz of a bundle whose content
-- hash (the scheme of `botfiles`) is `sha256`. Stored once however many versions use it.
create table bundle (
    sha256 text primary key,
    -- the canonical .tar.gz
    archive blob not null,
    -- regular files and bytes of content, unpacked
    files integer not null,
    bytes integer not null,
    created_at integer not null
);

-- the version's files as uploaded (= files_sha256); null for a bot registered from a
-- local folder (`mazearena tournament`), which plays from `dir` on that machine
alter table bot_version add column bundle_sha256 text references bundle (sha256);
-- the version's folder after its build (null: no build, or not built yet)
alter table bot_version add column built_sha256 text references bundle (sha256);
-- the worker building the version, and until when its claim holds
alter table bot_version add column build_owner text;
alter table bot_version add column build_lease_expires_at integer;
