"""The system description: parameters (one schema), the paper's Table 2, the FE rotor, methods A-J as data."""
