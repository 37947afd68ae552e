"""Pictures of episodes: recorded traces, still renders (PNG) and animations (GIF); each env draws its world."""
