"""Case files (TOML) and their schema, the bundled default case, the paper's validation cases."""
