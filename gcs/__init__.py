"""Fleet GCS: the shared wire protocol and the `gcs` command line."""

__version__ = "0.1.0"
