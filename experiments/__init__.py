"""The reproduction pipeline, its report and the selector sweep: run from the repository root."""
