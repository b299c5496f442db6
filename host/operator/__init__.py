"""What a person tells the running daemon: quarantines and holds, over a local-only socket."""
