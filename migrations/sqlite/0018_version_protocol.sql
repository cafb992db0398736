-- mazearena schema, version 18: a version may be a mouse of the mms simulator, spoken to
-- through the referee's translation (docs/PROTOCOL-mms.md). Never edit an applied
-- migration: add a new file.
-- `mms`, or null for protocol v1.
alter table bot_version add column protocol text;
