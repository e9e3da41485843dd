mod camera;
mod scene;
mod viewer;
mod surfaces;
