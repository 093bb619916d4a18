//! The `drape` command line: argument parsing and subcommands; nothing numerical lives here.
