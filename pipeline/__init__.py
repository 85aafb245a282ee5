"""The DVC pipeline's stage programs: thin wrappers that read params.yaml, call bogie and write outputs."""
