"""What every layer stands on: errors and exit kinds, where data lives, strict JSON reading, JSON-schema
validation, input warnings, and rotations/poses (one convention)."""
