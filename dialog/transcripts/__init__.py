"""What is recorded: JSON Lines transcripts and their lock, turns as records and back, resuming by replay."""
