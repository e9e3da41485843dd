mod camera;
mod scene;
mod surfaces;
mod viewer;
