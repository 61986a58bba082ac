"""What the elastic deployment path prescribes at every t: one module per driver and their registry."""
