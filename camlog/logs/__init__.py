"""Commands over whole logs: convert between formats, play in time, import image folders,
summarize."""
