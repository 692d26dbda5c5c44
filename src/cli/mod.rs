pub mod optimize;
