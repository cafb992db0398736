//! The one integration-test binary (one link step for CI): real files, real processes.

mod api;
mod authors;
mod bots;
mod browser;
mod cli;
mod client;
mod competitions;
mod connections;
mod contain;
mod crowd;
mod deploy;
mod faults;
mod hostile;
mod load;
mod mazefiles;
mod mms;
mod pages;
mod rankings;
mod readme;
mod referee;
mod runner;
mod sessions;
mod support;
mod take_part;
mod upgrade;
mod web;
