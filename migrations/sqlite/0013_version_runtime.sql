-- mazearena schema, version 13: a version may name the runtime it wants first on its
-- PATH (one of the server's runtimes, by name: GET /api/runtimes). Never edit an
-- applied migration: add a new file.
alter table bot_version add column runtime text;
