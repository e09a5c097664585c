"""The meshcat mirror of the kitchen: scene reading, meshcat objects, the server process, recording,
export and screenshots."""
